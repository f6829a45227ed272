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
    let residual = plan.residuals(&values, 3, &[2; 3]).unwrap().unwrap();
    let mut integer = plan.clone();
    integer.exact_in_float = false;
    assert_eq!(
        integer.residuals(&values, 3, &[2; 3]).unwrap().unwrap(),
        residual
    );
    let transpose = |m: &[i64]| -> Vec<i64> {
        (0..3)
            .flat_map(|c| (0..count).map(move |v| m[v * 3 + c]))
            .collect()
    };
    let mut columns = transpose(&residual);
    let mut other = columns.clone();
    plan.restore_columns(&mut columns, count, &[2; 3]).unwrap();
    integer.restore_columns(&mut other, count, &[2; 3]).unwrap();
    assert_eq!(columns, transpose(&values));
    assert_eq!(other, transpose(&values));
}

#[test]
fn out_of_range_is_refused() {
    let (faces, count) = grid(4);
    let plan = plan_of(&faces, 4, count);
    let mut column = vec![1i64 << 31; count];
    assert_eq!(
        plan.restore_columns(&mut column, count, &[2]).unwrap_err(),
        MEAN_RANGE
    );
    let mut short = vec![0i64; count - 1];
    assert!(plan.restore_columns(&mut short, count - 1, &[2]).is_err());
    assert!(plan.restore_columns(&mut short, count, &[2]).is_err());
    assert!(plan.restore_columns(&mut [], count, &[]).is_ok());
    let too_large = vec![MEAN_LIMIT + 1; count];
    assert_eq!(plan.residuals(&too_large, 1, &[2]).unwrap(), None);
    assert_eq!(plan.residual_columns(&too_large, 1, &[2]).unwrap(), None);
}

#[test]
fn minus_two_to_the_63_is_out_of_range() {
    // its abs() wraps to itself: compared by abs, it would pass every range check
    let (faces, count) = grid(4);
    let plan = plan_of(&faces, 4, count);
    let mut values = vec![0; count];
    values[0] = i64::MIN;
    assert_eq!(plan.residuals(&values, 1, &[2]).unwrap(), None);
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
    let residual = plan.residuals(&values, width, &[2; 19]).unwrap().unwrap();
    let mut columns: Vec<i64> = (0..width)
        .flat_map(|c| residual.iter().skip(c).step_by(width).copied())
        .collect();
    let (planes, raw) = crate::streams::pack_planes(&columns);
    let steps: Vec<f32> = (0..width).map(|c| 0.001 * (c as f32 + 1.0)).collect();
    plan.restore_columns(&mut columns, count, &[2; 19]).unwrap();
    let mut integer = plan.clone();
    integer.exact_in_float = false;
    for threads in [1, 2, 3] {
        for plan in [&plan, &integer] {
            let mut out = vec![0.0; count * width];
            plan.restore_values(&raw, planes, count, &steps, &mut out, threads, &[2; 19])
                .unwrap();
            assert_scaled(&out, &columns, count, &steps);
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
        .restore_values(&[0; 5], 1, count, &steps, &mut out, 2, &[2; 9])
        .is_err());
    let mut short = vec![0.0; (count - 1) * 9];
    let raw = vec![0u8; (count - 1) * 9];
    assert!(plan
        .restore_values(&raw, 1, count - 1, &steps, &mut short, 2, &[2; 9])
        .is_err());
    // residuals that push a restored value beyond 2**32, in the last block only
    let mut stream = vec![0i64; count * 9];
    for v in 0..count {
        stream[8 * count + v] = (1 << 31) - 1;
    }
    let (planes, raw) = crate::streams::pack_planes(&stream);
    for threads in [1, 2] {
        let result = plan.restore_values(&raw, planes, count, &steps, &mut out, threads, &[2; 9]);
        assert_eq!(result, Err(MEAN_RANGE.to_string()));
    }
}

/// A mesh of `faces` random triangles over `count` vertices (some vertices on no face).
fn random_triangles(count: usize, faces: usize, seed: u64) -> Vec<i64> {
    pseudo_random(faces * 3, seed, count as i64)
        .into_iter()
        .map(|v| v.rem_euclid(count as i64))
        .collect()
}

/// Predictor 2 with a push, straight from the spec (§6.2, *Push*) in i128: row j's prediction
/// from `column` (one column's values by vertex).
fn reference_prediction(steps: &topology::MeanStepsArrays, j: usize, column: &[i64], a: u8) -> i64 {
    let a = i128::from(a);
    let mut v = 0i128;
    for k in steps.source_ends[j]..steps.source_ends[j + 1] {
        let (w, anchor) = (steps.sources[k] as usize, steps.anchors[k] as usize);
        v += (6 + a) * i128::from(column[w]) - a * i128::from(column[anchor]);
    }
    let c = (steps.source_ends[j + 1] - steps.source_ends[j]) as i128;
    i64::try_from((2 * v + 6 * c).div_euclid(12 * c)).unwrap()
}

/// The residuals of a (count, width) matrix, row after row, with the reference predictions.
fn reference_residuals(
    steps: &topology::MeanStepsArrays,
    values: &[i64],
    width: usize,
    push: &[u8],
) -> Vec<i64> {
    let count = values.len() / width;
    let mut out = values.to_vec();
    for (c, &a) in push.iter().enumerate() {
        let column: Vec<i64> = (0..count).map(|v| values[v * width + c]).collect();
        for (j, &row) in steps.rows.iter().enumerate() {
            out[row as usize * width + c] -= reference_prediction(steps, j, &column, a);
        }
    }
    out
}

/// The plan in float64 and the same plan forced through its integer paths.
fn both_paths(plan: &MeanPlan) -> [MeanPlan; 2] {
    let mut integer = plan.clone();
    integer.exact_in_float = false;
    integer.exact_in_float_pushed = false;
    [plan.clone(), integer]
}

fn transpose(matrix: &[i64], width: usize) -> Vec<i64> {
    let count = matrix.len() / width;
    (0..width)
        .flat_map(|c| (0..count).map(move |v| matrix[v * width + c]))
        .collect()
}

#[test]
fn pushes_match_the_reference_on_random_meshes() {
    let meshes = [
        (grid(7).0, 4, 49),
        (random_triangles(40, 70, 11), 3, 40),
        (random_triangles(60, 150, 12), 3, 60),
        (random_triangles(30, 200, 13), 3, 30),
    ];
    // 0..9 mixed in a block, a block of 2s, a block of one other push, a narrow block
    let push: Vec<u8> = (0..16)
        .map(|c| (c % 10) as u8)
        .chain([2; 16])
        .chain([7; 16])
        .chain([9, 0, 2, 5, 6])
        .collect();
    let width = push.len();
    for (seed, (faces, face_width, count)) in meshes.into_iter().enumerate() {
        let forest = Forest::new(&faces, face_width, count).unwrap();
        let steps = forest.mean_steps();
        let plan = MeanPlan::from_arrays(&steps, count);
        assert!(plan.exact_in_float_pushed);
        for span in [1i64 << 20, 1 << 31] {
            let values = pseudo_random(count * width, 100 + seed as u64, span);
            let expected = reference_residuals(&steps, &values, width, &push);
            let stream = transpose(&expected, width);
            let (planes, raw) = crate::streams::pack_planes(&stream);
            let scales: Vec<f32> = (0..width).map(|c| 0.25 * (c as f32 + 1.0)).collect();
            for plan in both_paths(&plan) {
                let residual = plan.residuals(&values, width, &push).unwrap().unwrap();
                assert_eq!(residual, expected, "mesh {seed}, span {span}");
                let columns = plan.residual_columns(&values, width, &push).unwrap();
                assert_eq!(columns.unwrap(), transpose(&expected, width));
                let mut columns = stream.clone();
                plan.restore_columns(&mut columns, count, &push).unwrap();
                assert_eq!(columns, transpose(&values, width));
                for threads in [1, 2] {
                    let mut out = vec![0.0; count * width];
                    plan.restore_values(&raw, planes, count, &scales, &mut out, threads, &push)
                        .unwrap();
                    for (slot, (&value, c)) in out.iter().zip(values.iter().zip((0..width).cycle()))
                    {
                        assert_eq!(*slot, value as f64 * f64::from(scales[c]));
                    }
                }
            }
        }
    }
}

/// Push 2 in a block of other pushes (the pushed sums) gives what push 2 alone (today's sums)
/// gives, and today's prediction `floor((2U + 3c) / 6c)`.
#[test]
fn push_two_is_todays_predictor() {
    let faces = random_triangles(50, 120, 21);
    let forest = Forest::new(&faces, 3, 50).unwrap();
    let steps = forest.mean_steps();
    let plan = MeanPlan::from_arrays(&steps, 50);
    let values = pseudo_random(50 * 3, 5, 1 << 32);
    let plain = plan.residuals(&values, 3, &[2, 2, 2]).unwrap().unwrap();
    let mixed = plan.residuals(&values, 3, &[2, 9, 2]).unwrap().unwrap();
    for v in 0..50 {
        assert_eq!(plain[v * 3], mixed[v * 3]);
        assert_eq!(plain[v * 3 + 2], mixed[v * 3 + 2]);
    }
    for c in 0..3 {
        let column: Vec<i64> = (0..50).map(|v| values[v * 3 + c]).collect();
        for (j, &row) in steps.rows.iter().enumerate() {
            let mut u = 0i128;
            for k in steps.source_ends[j]..steps.source_ends[j + 1] {
                u += 4 * i128::from(column[steps.sources[k] as usize])
                    - i128::from(column[steps.anchors[k] as usize]);
            }
            let count = (steps.source_ends[j + 1] - steps.source_ends[j]) as i128;
            let prediction = (2 * u + 3 * count).div_euclid(6 * count) as i64;
            assert_eq!(
                plain[row as usize * 3 + c],
                values[row as usize * 3 + c] - prediction
            );
        }
    }
}

#[test]
fn bad_pushes_are_errors() {
    let (faces, count) = grid(4);
    let plan = plan_of(&faces, 4, count);
    let values = vec![0i64; count * 2];
    for push in [&[2u8][..], &[2, 2, 2], &[2, 10], &[255, 2]] {
        for plan in both_paths(&plan) {
            assert!(plan.residuals(&values, 2, push).is_err(), "{push:?}");
            let mut columns = values.clone();
            assert!(plan.restore_columns(&mut columns, count, push).is_err());
            let raw = vec![0u8; count * 2];
            let mut out = vec![0.0; count * 2];
            assert!(plan
                .restore_values(&raw, 1, count, &[1.0; 2], &mut out, 1, push)
                .is_err());
        }
    }
    assert!(plan.restore_columns(&mut [], count, &[2]).is_err());
    assert!(plan.residuals(&[], 0, &[]).is_ok());
    assert!(check_push(&[0, 9], 2).is_ok());
}

/// A value pushed out of range is refused on both paths, whatever the push.
#[test]
fn pushed_values_out_of_range_are_refused() {
    let (faces, count) = grid(5);
    for a in [0u8, 5, 9] {
        for plan in both_paths(&plan_of(&faces, 4, count)) {
            let mut column = vec![(1i64 << 31) + 1; count];
            assert_eq!(
                plan.restore_columns(&mut column, count, &[a]).unwrap_err(),
                MEAN_RANGE
            );
        }
    }
}

/// A crafted row of 2**16 sources: push 2 still sums in float64, any other push in integers,
/// and both give the reference's results.
#[test]
fn a_row_of_many_sources_takes_the_integer_path_when_pushed() {
    let sources = PUSHED_FLOAT_SOURCES;
    let count = sources + 1;
    let steps = topology::MeanStepsArrays {
        rows: vec![sources as u32],
        step_ends: vec![0, 1],
        sources: (0..sources as u32).collect(),
        anchors: (0..sources as u32)
            .map(|w| (w + 1) % sources as u32)
            .collect(),
        source_ends: vec![0, sources],
        levels: 2,
    };
    let plan = MeanPlan::from_arrays(&steps, count);
    assert!(plan.exact_in_float && !plan.exact_in_float_pushed);
    let push = [2u8, 9, 0];
    let values = pseudo_random(count * 3, 17, 1 << 32);
    let expected = reference_residuals(&steps, &values, 3, &push);
    assert_eq!(
        plan.residuals(&values, 3, &push).unwrap().unwrap(),
        expected
    );
    let mut columns = transpose(&expected, 3);
    plan.restore_columns(&mut columns, count, &push).unwrap();
    assert_eq!(columns, transpose(&values, 3));
}

/// The adaptive stream (§6.14) of residual `columns` in the mesh order of `faces`, and the order.
fn adaptive_stream(
    faces: &[i64],
    count: usize,
    columns: &[i64],
) -> (Vec<u8>, crate::adaptive::CodingOrder) {
    let steps = Forest::new(faces, 4, count).unwrap().mean_steps();
    let order =
        crate::adaptive::CodingOrder::mesh(count, &steps.rows, &steps.sources, &steps.source_ends)
            .unwrap();
    let width = columns.len() / count;
    let payload = crate::adaptive::encode_columns(columns, width, count, &order).unwrap();
    (payload, order)
}

/// `restore_adaptive_values`: the same floats as decoding the stream, `restore_columns` and the
/// product by each column's step, on one thread or two, with pushes or without.
#[test]
fn restore_adaptive_values_matches_decoding_then_restoring() {
    let (faces, count) = grid(11);
    let plan = plan_of(&faces, 4, count);
    let width = 19; // two full blocks and a narrower one
    let values = pseudo_random(count * width, 5, 1 << 20);
    let steps: Vec<f32> = (0..width).map(|c| 0.001 * (c as f32 + 1.0)).collect();
    for push in [[2u8; 19], [0, 1, 2, 3].repeat(5)[..19].try_into().unwrap()] {
        let residual = plan.residuals(&values, width, &push).unwrap().unwrap();
        let mut columns: Vec<i64> = (0..width)
            .flat_map(|c| residual.iter().skip(c).step_by(width).copied())
            .collect();
        let (payload, order) = adaptive_stream(&faces, count, &columns);
        plan.restore_columns(&mut columns, count, &push).unwrap();
        for threads in [1, 2] {
            let mut out = vec![0.0; count * width];
            plan.restore_adaptive_values(&payload, &order, 3, &steps, &mut out, threads, &push)
                .unwrap()
                .unwrap();
            assert_scaled(&out, &columns, count, &steps);
        }
    }
}

/// Its errors in the reference's order: the stream's, then an integer outside the planes, then
/// a value out of range; a caller's sizes.
#[test]
fn restore_adaptive_values_refuses_in_order() {
    let (faces, count) = grid(5);
    let plan = plan_of(&faces, 4, count);
    let steps = [1.0f32; 9];
    let mut out = vec![0.0; count * 9];
    // residuals that push a restored value beyond 2**32, in the first block, and one integer
    // beyond four planes in the last: the planes' error is the one reported
    let mut stream = vec![0i64; count * 9];
    stream[..count].fill((1 << 31) - 1);
    let (payload, order) = adaptive_stream(&faces, count, &stream);
    let mut wide = stream.clone();
    wide[8 * count + 3] = 1 << 31;
    let (wide_payload, _) = adaptive_stream(&faces, count, &wide);
    let planes_error = "an integer of the adaptive stream does not fit its 4 planes";
    for threads in [1, 2] {
        let mut restore = |payload: &[u8], planes: usize| {
            plan.restore_adaptive_values(
                payload, &order, planes, &steps, &mut out, threads, &[2; 9],
            )
        };
        assert_eq!(restore(&payload, 4), Ok(Err(MEAN_RANGE.to_string())));
        assert_eq!(restore(&wide_payload, 5), Ok(Err(MEAN_RANGE.to_string())));
        let refused = restore(&wide_payload, 4).unwrap_err();
        assert_eq!(
            (refused.rule, refused.detail.as_str()),
            (crate::adaptive::RULE, planes_error)
        );
        // and the stream's error before both
        let cut = restore(&wide_payload[..wide_payload.len() - 2], 4).unwrap_err();
        assert_eq!(
            cut.detail,
            "the adaptive stream ends before its last integer"
        );
    }
    // sizes that do not fit: the columns, the planes, the pushes
    let mut short = vec![0.0; count * 9 - 1];
    let caller = |result: Result<Result<(), PredictionError>, _>| matches!(result, Ok(Err(_)));
    assert!(caller(plan.restore_adaptive_values(
        &payload, &order, 5, &steps, &mut short, 1, &[2; 9]
    )));
    assert!(caller(plan.restore_adaptive_values(
        &payload, &order, 9, &steps, &mut out, 1, &[2; 9]
    )));
    assert!(caller(plan.restore_adaptive_values(
        &payload, &order, 5, &steps, &mut out, 1, &[2; 8]
    )));
}

/// `out` (row-major, one column per step) is each restored column (column-major, `count` rows)
/// times its step, bit for bit.
fn assert_scaled(out: &[f64], columns: &[i64], count: usize, steps: &[f32]) {
    for (v, row) in out.chunks_exact(steps.len()).enumerate() {
        for (c, &value) in row.iter().enumerate() {
            let expected = columns[c * count + v] as f64 * f64::from(steps[c]);
            assert_eq!(value.to_bits(), expected.to_bits());
        }
    }
}

/// `push_costs`'s prices by the plain route: each push's residuals from `residuals`, each
/// column's `bits[|r|]` summed row after row (or pairwise where `alone`), over the rows.
fn reference_push_costs(
    plan: &MeanPlan,
    values: &[i64],
    width: usize,
    bits: &[f64],
    alone: Option<usize>,
) -> Vec<f64> {
    let height = values.len() / width;
    let mut out = vec![0.0; width * PUSH_COUNT];
    for a in 0..=MAX_PUSH {
        let residual = plan
            .residuals(values, width, &vec![a; width])
            .unwrap()
            .unwrap();
        for c in 0..width {
            let prices: Vec<f64> = (0..height)
                .map(|v| {
                    let m = residual[v * width + c].unsigned_abs() as usize;
                    bits.get(m).copied().unwrap_or(f64::NAN)
                })
                .collect();
            let sum = if alone == Some(c) {
                numpy_pairwise_sum(&prices)
            } else {
                prices.iter().fold(0.0, |sum, &p| sum + p)
            };
            out[c * PUSH_COUNT + usize::from(a)] = sum / height as f64;
        }
    }
    for row in out.chunks_exact_mut(PUSH_COUNT) {
        if row.iter().any(|p| p.is_nan()) {
            row.fill(f64::NAN);
        }
    }
    out
}

fn same_prices(fast: &[f64], reference: &[f64]) -> bool {
    fast.len() == reference.len()
        && fast
            .iter()
            .zip(reference)
            .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()))
}

#[test]
fn push_costs_price_every_push_as_the_residuals_do() {
    // prices that differ in their last bits from value to value, so that any change of order
    // or of residual shows
    let bits: Vec<f64> = (0..300).map(|m| (1.0 + 2.0 * m as f64).log2()).collect();
    let meshes = [
        (grid(7).0, 4, 49),
        (random_triangles(40, 70, 11), 3, 40),
        (random_triangles(60, 150, 12), 3, 60),
    ];
    for (seed, (faces, face_width, count)) in meshes.into_iter().enumerate() {
        let plan = plan_of(&faces, face_width, count);
        // 17 columns: the last is alone in its block of 16 and summed pairwise; 33 in
        // blocks of 8 leaves it alone too; 18 leaves none alone
        for (width, block, span) in [(17, 16, 60), (33, 8, 200), (18, 16, 5), (1, 16, 40)] {
            let values = pseudo_random(count * width, 40 + seed as u64, span);
            let alone = (width % block == 1).then_some(width - 1);
            let expected = reference_push_costs(&plan, &values, width, &bits, alone);
            assert!(expected.iter().any(|p| p.is_nan()) == (span == 200));
            for plan in both_paths(&plan) {
                let fast = plan
                    .push_costs(&values, width, &bits, block)
                    .unwrap()
                    .unwrap();
                assert!(same_prices(&fast, &expected), "mesh {seed}, width {width}");
            }
        }
    }
}

#[test]
fn push_costs_refuse_what_residuals_refuse() {
    let (faces, count) = grid(4);
    let plan = plan_of(&faces, 4, count);
    let bits = [0.0, 1.0];
    let too_large = vec![MEAN_LIMIT + 1; count];
    assert_eq!(plan.push_costs(&too_large, 1, &bits, 16).unwrap(), None);
    assert!(plan.push_costs(&[0; 3], 1, &bits, 16).is_err());
    assert!(plan.push_costs(&vec![0; count], 1, &bits, 0).is_err());
    assert_eq!(
        plan.push_costs(&[], 0, &bits, 16).unwrap(),
        Some(Vec::new())
    );
    // an empty table prices every column NaN
    let zeros = vec![0; count * 2];
    let prices = plan.push_costs(&zeros, 2, &[], 16).unwrap().unwrap();
    assert!(prices.len() == 2 * PUSH_COUNT && prices.iter().all(|p| p.is_nan()));
}

#[test]
fn pairwise_sum_is_numpys() {
    // numpy's order, written out for 9 values (8 partial sums, then the ninth) and for 300
    // (halves of 144 and 156, each unrolled by 8): values whose sums round differently in
    // another order
    let values: Vec<f64> = (0..300)
        .map(|i| 1.0 + f64::from(i) * 1e-3 + 1e16 * f64::from(i % 3))
        .collect();
    let nine = &values[..9];
    let eight =
        ((nine[0] + nine[1]) + (nine[2] + nine[3])) + ((nine[4] + nine[5]) + (nine[6] + nine[7]));
    assert_eq!(
        numpy_pairwise_sum(nine).to_bits(),
        (eight + nine[8]).to_bits()
    );
    let halves = numpy_pairwise_sum(&values[..144]) + numpy_pairwise_sum(&values[144..]);
    assert_eq!(numpy_pairwise_sum(&values).to_bits(), halves.to_bits());
    assert_eq!(
        numpy_pairwise_sum(&values[..3]),
        values[0] + values[1] + values[2]
    );
    assert_eq!(numpy_pairwise_sum(&[]), 0.0);
}
