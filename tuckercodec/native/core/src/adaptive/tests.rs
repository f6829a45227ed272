use super::*;
use crate::test_random::Random;

impl Random {
    /// Mostly small signed integers, some zero, now and then one of any size below 2**62.
    fn integer(&mut self) -> i64 {
        let r = self.next();
        let magnitude = match r % 8 {
            0 | 1 => 0,
            2..=5 => (r >> 8) % 40,
            6 => (r >> 8) % 100_000,
            _ => (r >> 8) >> (r >> 58),
        } as i64;
        if r & 128 != 0 {
            -magnitude
        } else {
            magnitude
        }
    }
}

fn hex(text: &str) -> Vec<u8> {
    (0..text.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&text[i..i + 2], 16).unwrap())
        .collect()
}

/// The (cols, rows) = (3, 5) matrix and the mesh order of the bytes below, which
/// `tuckercodec/format/adaptive.py` wrote.
const VALUES: [i64; 15] = [
    0,
    1,
    -2,
    3,
    100,
    5,
    -7,
    0,
    1 << 40,
    -(1 << 62),
    1,
    2,
    3,
    4,
    5,
];
const SEQUENCE_BYTES: &str =
    "004e56bd263790ffffffffd765d697000b2effffffffe561c7c0000000000c0f50f7e53000";
const MESH_BYTES: &str =
    "007605f97deecb7ffffff0d3885600040c8fffffffffec18c161000000000914e996c90000";

fn small_mesh() -> CodingOrder {
    CodingOrder::mesh(5, &[3, 1, 4], &[0, 2, 0, 3, 2, 3, 1], &[0, 2, 5, 7]).unwrap()
}

fn rule_and_detail(result: Result<Vec<i64>, Broken>) -> (&'static str, String) {
    let error = result.unwrap_err();
    (error.rule, error.detail)
}

#[test]
fn the_reference_bytes() {
    let sequence = CodingOrder::sequence(5);
    let encoded = encode_columns(&VALUES, 3, 5, &sequence).unwrap();
    assert_eq!(encoded, hex(SEQUENCE_BYTES));
    assert_eq!(decode_columns(&encoded, 3, &sequence).unwrap(), VALUES);
    let mesh = small_mesh();
    let encoded = encode_columns(&VALUES, 3, 5, &mesh).unwrap();
    assert_eq!(encoded, hex(MESH_BYTES));
    assert_eq!(decode_columns(&encoded, 3, &mesh).unwrap(), VALUES);
    // nothing to code: the five bytes of the coder's ending
    let empty = encode_columns(&[], 0, 0, &CodingOrder::sequence(0)).unwrap();
    assert_eq!(empty, vec![0; 5]);
    assert_eq!(
        decode_columns(&empty, 0, &CodingOrder::sequence(0)).unwrap(),
        Vec::<i64>::new()
    );
}

#[test]
fn the_mesh_order_is_the_references() {
    let mesh = small_mesh();
    let expected = CodingOrder::new(
        &[0, 2, 3, 1, 4],
        &[0, 2, 0, 3, 2, 3, 1],
        &[0, 0, 0, 2, 5, 7],
        true,
        5,
    )
    .unwrap();
    assert_eq!(mesh, expected);
    let sequence = CodingOrder::new(&[0, 1, 2, 3], &[0, 1, 0, 2, 1], &[0, 0, 1, 3, 5], false, 4);
    assert_eq!(sequence.unwrap(), CodingOrder::sequence(4));
}

#[test]
fn random_matrices_round_trip() {
    let mut random = Random(0x9E37_79B9_7F4A_7C15);
    for (cols, rows) in [(1, 1), (1, 7), (7, 1), (3, 50), (12, 33), (2, 400)] {
        let values: Vec<i64> = (0..cols * rows).map(|_| random.integer()).collect();
        for order in [CodingOrder::sequence(rows), reversed(rows)] {
            let encoded = encode_columns(&values, cols, rows, &order).unwrap();
            // the encoder's fast loop writes the general loop's bytes
            assert_eq!(
                encode_columns(&values, cols, rows, &general(&order)).unwrap(),
                encoded
            );
            assert_eq!(decode_columns(&encoded, cols, &order).unwrap(), values);
        }
    }
}

/// Descending rows, each after the rows after it: a mesh-like order of another shape.
fn reversed(rows: usize) -> CodingOrder {
    let order: Vec<i64> = (0..rows as i64).rev().collect();
    let mut sources = Vec::new();
    let mut ends = vec![0i64];
    for &row in &order {
        sources.extend((row + 1..rows as i64).take(3));
        ends.push(sources.len() as i64);
    }
    CodingOrder::new(&order, &sources, &ends, true, rows).unwrap()
}

#[test]
fn the_largest_magnitudes() {
    let values = [i64::MAX, -i64::MAX, 1 << 62, -(1 << 62), 3, i64::MAX - 1];
    let order = CodingOrder::sequence(3);
    let encoded = encode_columns(&values, 2, 3, &order).unwrap();
    assert_eq!(decode_columns(&encoded, 2, &order).unwrap(), values);
    // 2**63 takes 63 exponent decisions 1: written, but no decoder takes it
    let encoded = encode_columns(&[i64::MIN], 1, 1, &CodingOrder::sequence(1)).unwrap();
    assert_eq!(encoded, hex("00fffffffefffe13924d000000000000000000"));
    assert_eq!(
        rule_and_detail(decode_columns(&encoded, 1, &CodingOrder::sequence(1))),
        (
            RULE,
            "an integer of the adaptive stream has more than 62 bits".into()
        )
    );
}

#[test]
fn damaged_streams_are_r46() {
    let order = CodingOrder::sequence(5);
    let good = hex(SEQUENCE_BYTES);
    let ends_early = (
        RULE,
        "the adaptive stream ends before its last integer".to_string(),
    );
    assert_eq!(
        rule_and_detail(decode_columns(&good[..good.len() - 1], 3, &order)),
        ends_early
    );
    assert_eq!(
        rule_and_detail(decode_columns(&good[..6], 3, &order)),
        ends_early
    );
    let mut longer = good.clone();
    longer.extend([0, 0]);
    assert_eq!(
        rule_and_detail(decode_columns(&longer, 3, &order)),
        (
            RULE,
            "the adaptive stream holds 2 bytes after its last integer".into()
        )
    );
    let start = (
        RULE,
        "an adaptive stream starts with a zero byte and holds at least 5 bytes".to_string(),
    );
    let mut first = good.clone();
    first[0] = 1;
    assert_eq!(rule_and_detail(decode_columns(&first, 3, &order)), start);
    assert_eq!(
        rule_and_detail(decode_columns(&good[..4], 0, &order)),
        start
    );
    // fewer integers than coded: bytes left over
    assert_eq!(decode_columns(&good, 2, &order).unwrap_err().rule, RULE);
    // a code at or above the range at the end
    assert_eq!(
        rule_and_detail(decode_columns(&[0, 0xFF, 0xFF, 0xFF, 0xFF], 0, &order)),
        (
            RULE,
            "the adaptive stream's last bytes are not a range coder's ending".into()
        )
    );
}

#[test]
fn every_damage_is_an_error_or_integers() {
    let order = small_mesh();
    let good = hex(MESH_BYTES);
    for at in 0..good.len() {
        for flip in [1u8, 0x80, 0xFF] {
            let mut damaged = good.clone();
            damaged[at] ^= flip;
            if let Ok(values) = decode_columns(&damaged, 3, &order) {
                // whatever it decodes to codes back to a stream of the same integers
                let again = encode_columns(&values, 3, 5, &order).unwrap();
                assert_eq!(decode_columns(&again, 3, &order).unwrap(), values);
            }
        }
    }
}

#[test]
fn too_many_integers_for_the_payload() {
    let order = CodingOrder::sequence(1 << 20);
    assert_eq!(
        rule_and_detail(decode_columns(&[0; 5], 1 << 20, &order)),
        (
            RULE,
            "1099511627776 integers cannot come from 5 bytes (at most 32768 per byte)".into()
        )
    );
    assert!(check_size(usize::MAX, usize::MAX, usize::MAX).is_err());
    assert!(check_size(32768, 5, 5).is_ok());
    assert!(check_size(32769, 5, 5).is_err());
    // a matrix whose columns do not fill the output
    let mut out = vec![0i64; 7];
    assert_eq!(
        decode_columns_into(&[0; 5], &CodingOrder::sequence(2), &mut out)
            .unwrap_err()
            .rule,
        RULE
    );
}

#[test]
fn invalid_orders_are_refused() {
    assert!(CodingOrder::new(&[0, 3], &[], &[0, 0, 0], true, 3).is_err());
    assert!(CodingOrder::new(&[0, -1], &[], &[0, 0, 0], true, 3).is_err());
    assert!(CodingOrder::new(&[0, 1], &[5], &[0, 0, 1], true, 3).is_err());
    assert!(CodingOrder::new(&[0, 1], &[0], &[0, 0], true, 3).is_err());
    assert!(CodingOrder::new(&[0, 1], &[0], &[0, 1, 0], true, 3).is_err());
    assert!(CodingOrder::new(&[0, 1], &[0], &[0, 0, 2], true, 3).is_err());
    assert!(CodingOrder::new(&[0, 1], &[0], &[-1, 0, 1], true, 3).is_err());
    assert!(CodingOrder::mesh(3, &[3], &[], &[0, 0]).is_err());
    assert!(CodingOrder::mesh(3, &[1], &[0], &[0, 2]).is_err());
    // rows missing or twice are the reference's business, not an error
    let order = CodingOrder::new(&[1, 1], &[], &[0, 0, 0], true, 3).unwrap();
    let encoded = encode_columns(&[4, 5, 6], 1, 3, &order).unwrap();
    assert_eq!(decode_columns(&encoded, 1, &order).unwrap(), [0, 5, 0]);
    assert!(encode_columns(&[1, 2], 1, 3, &order).is_err());
    assert!(encode_columns(&[1, 2, 3], 1, 3, &CodingOrder::sequence(2)).is_err());
}

#[test]
fn classes_at_their_edges() {
    let mut left = [0u8; 4];
    left_classes(
        Some(&[0, 1, -8, i64::MIN]),
        Some(&[1, 0, 0, i64::MIN]),
        &mut left,
    );
    assert_eq!(left, [1, 2, 5, 5]);
    let mesh = small_mesh();
    let column = [i64::MIN, i64::MAX, 0, 1, 1];
    assert_eq!(mesh.neighbour_class(&column, &[]), 0);
    assert_eq!(mesh.neighbour_class(&column, &[2]), 1);
    assert_eq!(mesh.neighbour_class(&column, &[3]), 3); // 3 * 1 = 3: bit length 2
    assert_eq!(mesh.neighbour_class(&column, &[3, 4, 2]), 3); // floor(6 / 3) = 2
    assert_eq!(mesh.neighbour_class(&column, &[0, 1, 0]), 15);
    let sequence = CodingOrder::sequence(5);
    assert_eq!(sequence.neighbour_class(&column, &[3]), 3);
    assert_eq!(sequence.neighbour_class(&column, &[3, 2]), 3); // 2 * 1 + 0: bit length 2
    assert_eq!(sequence.neighbour_class(&column, &[2, 3]), 2); // 0 + 1
    assert_eq!(sequence.neighbour_class(&column, &[0, 0]), 15);
    // a mean of many sources whose sum passes 2**64, exact in 128 bits
    let big = [i64::MAX; 8];
    let sources = [0usize; 8];
    assert_eq!(
        mean_magnitude(&sources, |w| big[w].unsigned_abs()),
        3 * (i64::MAX as u128)
    );
}

/// `order` without its fast loop: the general one decodes it.
fn general(order: &CodingOrder) -> CodingOrder {
    CodingOrder {
        proper: None,
        ..order.clone()
    }
}

#[test]
fn the_orders_of_files_take_the_fast_loop() {
    // the sequence's arrays, however made, are known without them
    for rows in [0, 1, 2, 3, 7] {
        let sequence = CodingOrder::sequence(rows);
        assert_eq!(sequence.proper, Some(Proper::Sequence));
        let again = CodingOrder::new(
            &sequence.rows.iter().map(|&r| r as i64).collect::<Vec<_>>(),
            &sequence
                .sources
                .iter()
                .map(|&r| r as i64)
                .collect::<Vec<_>>(),
            &sequence.ends.iter().map(|&r| r as i64).collect::<Vec<_>>(),
            false,
            rows,
        );
        assert_eq!(again.unwrap().proper, Some(Proper::Sequence));
    }
    // the same arrays averaged, or a source other than the two rows before: listed
    let averaged = CodingOrder::new(&[0, 1, 2], &[0, 1, 0], &[0, 0, 1, 3], true, 3).unwrap();
    assert!(matches!(averaged.proper, Some(Proper::Listed { .. })));
    let other = CodingOrder::new(&[0, 1, 2], &[0, 0, 1], &[0, 0, 1, 3], false, 3).unwrap();
    assert!(matches!(other.proper, Some(Proper::Listed { .. })));
    assert!(small_mesh().proper.is_some());
    assert!(reversed(9).proper.is_some());
    // a row twice, a row missing, a source not coded yet, a source coded after
    let improper = [
        CodingOrder::new(&[1, 1], &[], &[0, 0, 0], true, 2),
        CodingOrder::new(&[1], &[], &[0, 0], true, 2),
        CodingOrder::new(&[0, 1], &[1], &[0, 1, 1], true, 2),
        CodingOrder::new(&[0, 1], &[0], &[0, 0, 1], true, 2),
    ];
    let proper = [false, false, false, true];
    for (order, expected) in improper.into_iter().zip(proper) {
        assert_eq!(order.unwrap().proper.is_some(), expected);
    }
}

#[test]
fn the_mean_class_is_the_divisions() {
    let mut random = Random(0x0123_4567_89AB_CDEF);
    let mut pairs: Vec<(u64, u64)> = Vec::new();
    for x in 0..200 {
        for count in 1..40 {
            pairs.push((x, count));
        }
    }
    for _ in 0..20000 {
        let (r, s) = (random.next(), random.next());
        let x = r >> (r % 64);
        let count = 1 + (s >> (s % 63 + 1)).min(x.max(1));
        pairs.push((x, count));
        // the edges: a multiple of count by a power of two, and one less
        let k = s % 40;
        if count << k >> k == count {
            pairs.push((count << k, count));
            pairs.push(((count << k) - 1, count));
        }
    }
    pairs.extend([
        (u64::MAX, 1),
        (u64::MAX, u64::MAX),
        (u64::MAX - 1, u64::MAX),
        (0, 1),
    ]);
    for (x, count) in pairs {
        assert_eq!(
            mean_class(x, count),
            magnitude_class(x / count),
            "{x} / {count}"
        );
    }
}

/// Random integers with magnitudes around the fast loop's saturation and far beyond it.
fn large_integers(random: &mut Random, count: usize) -> Vec<i64> {
    (0..count)
        .map(|_| {
            let r = random.next();
            let magnitude = match r % 4 {
                0 => 0,
                1 => i64::from(MAGNITUDE_CAP) + (r >> 60) as i64 - 8,
                2 => (r >> 2) as i64 >> (r % 64),
                _ => ((r >> 8) % 50) as i64,
            };
            if r & 256 != 0 {
                -magnitude
            } else {
                magnitude
            }
        })
        .collect()
}

/// A mesh-like order where row r's sources are up to `width` rows before it, chosen at random
/// (`mesh`: averaged; else the first two count).
fn random_order(random: &mut Random, rows: usize, width: usize, mesh: bool) -> CodingOrder {
    let mut sources = Vec::new();
    let mut ends = vec![0i64];
    for r in 0..rows as u64 {
        let count = random.next() % (width as u64 + 1);
        for _ in 0..count.min(r) {
            sources.push((random.next() % r) as i64);
        }
        ends.push(sources.len() as i64);
    }
    let order: Vec<i64> = (0..rows as i64).collect();
    CodingOrder::new(&order, &sources, &ends, mesh, rows).unwrap()
}

#[test]
fn the_fast_loops_code_as_the_general_ones() {
    let mut random = Random(0x5DEE_CE66_D1CE_4E5B);
    for (cols, rows, width) in [(3, 40, 3), (5, 200, 8), (2, 300, 40), (1, 1, 1)] {
        let orders = [
            random_order(&mut random, rows, width, true),
            random_order(&mut random, rows, width, false),
            CodingOrder::sequence(rows),
            reversed(rows),
        ];
        for order in orders {
            assert!(order.proper.is_some());
            let values = large_integers(&mut random, cols * rows);
            let encoded = encode_columns(&values, cols, rows, &order).unwrap();
            assert_eq!(
                encode_columns(&values, cols, rows, &general(&order)).unwrap(),
                encoded
            );
            assert_eq!(decode_columns(&encoded, cols, &order).unwrap(), values);
            assert_eq!(
                decode_columns(&encoded, cols, &general(&order)).unwrap(),
                values
            );
            // damaged streams: the same integers or the same error, either way
            for at in (0..encoded.len()).step_by(encoded.len() / 16 + 1) {
                let mut damaged = encoded.clone();
                damaged[at] ^= (random.next() as u8) | 1;
                for length in [damaged.len(), damaged.len() - 1, at + 1] {
                    let payload = &damaged[..length];
                    assert_eq!(
                        decode_columns(payload, cols, &order),
                        decode_columns(payload, cols, &general(&order))
                    );
                }
            }
        }
    }
}

/// `decode_runs` over every kind of order: the runs of `decode_columns`' integers, whatever the
/// buffers handed to it held (reused, too short, too long), and its errors.
#[test]
fn runs_into_reused_buffers_are_the_columns() {
    let mut random = Random(0x2545_F491_4F6C_DD1D);
    let (cols, rows) = (7, 60);
    let orders = [
        random_order(&mut random, rows, 6, true),
        CodingOrder::sequence(rows),
        general(&reversed(rows)),
    ];
    for order in orders {
        let values = large_integers(&mut random, cols * rows);
        let encoded = encode_columns(&values, cols, rows, &order).unwrap();
        for block in [1, 3, 7, 10] {
            let mut sizes = [0, 5, 4 * rows, 50 * rows].into_iter().cycle();
            let mut runs = Vec::new();
            decode_runs(
                &encoded,
                &order,
                cols,
                block,
                || vec![-1; sizes.next().unwrap()],
                |first, run| runs.push((first, run)),
            )
            .unwrap();
            let firsts: Vec<usize> = runs.iter().map(|(first, _)| *first).collect();
            assert_eq!(firsts, (0..cols).step_by(block).collect::<Vec<_>>());
            let joined: Vec<i64> = runs.into_iter().flat_map(|(_, run)| run).collect();
            assert_eq!(joined, values);
        }
        // the errors of decode_columns, whichever way it is decoded
        for length in [0, 3, encoded.len() - 1] {
            let payload = &encoded[..length];
            let runs = decode_runs(payload, &order, cols, 2, Vec::new, |_, _| {});
            assert_eq!(runs, decode_columns(payload, cols, &order).map(|_| ()));
        }
        let refused = decode_runs(&encoded[..1], &order, 32768 * rows, 2, Vec::new, |_, _| {});
        assert_eq!(refused.unwrap_err().rule, RULE);
    }
}

/// The decoder's loop makes a position's context before the integer before it is decoded,
/// except where that integer is one of its sources: the flag says which, by position.
#[test]
fn positions_after_their_source_are_flagged() {
    let flags = |order: &CodingOrder| match &order.proper {
        Some(Proper::Listed { steps, .. }) => steps
            .iter()
            .map(|step| step.count & AFTER_SOURCE != 0)
            .collect::<Vec<_>>(),
        _ => panic!("a listed order"),
    };
    // each row after the rows after it: every position but the first follows a source
    assert_eq!(flags(&reversed(4)), [false, true, true, true]);
    // rows 3, 1, 4 after the roots 0 and 2: row 3 (sources 0, 2) follows root 2, row 1
    // (sources 0, 3, 2) follows row 3, row 4 (sources 3, 1) follows row 1
    assert_eq!(flags(&small_mesh()), [false, false, true, true, true]);
    let spread = CodingOrder::new(&[0, 1, 2], &[0], &[0, 0, 0, 1], true, 3).unwrap();
    assert_eq!(flags(&spread), [false, false, false]);
}

/// The fast loop's mean of up to four sources, a product and a shift: floor(3 total / count)
/// exactly, up to the largest total of saturated magnitudes.
#[test]
fn the_scaled_mean_is_the_division() {
    let mut random = Random(0x1405_7B7E_F767_814F);
    let largest = 4 * u64::from(MAGNITUDE_CAP);
    let mut totals: Vec<u64> = (0..64).flat_map(|b| [1u64 << b, (1u64 << b) - 1]).collect();
    totals.extend((0..10_000).map(|_| random.next() % (largest + 1)));
    totals.retain(|&t| t <= largest);
    totals.push(largest);
    assert_eq!(mean_scale(0), 0);
    for count in 1..=FIRST_SOURCES {
        let scale = u64::from(mean_scale(count));
        for &total in &totals {
            assert_eq!((total * scale) >> MEAN_SHIFT, 3 * total / count as u64);
        }
    }
}
