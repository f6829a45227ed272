//! Unit tests of the walk: round trips, each error of the decoder word for word, and random
//! values that must never panic.

use super::{decode, encode, Streams};
use crate::test_random::Random;

fn streams<'a>(values: &'a [Vec<i64>; 4]) -> Streams<'a> {
    Streams {
        ops: &values[0],
        degrees: &values[1],
        vertices: &values[2],
        references: &values[3],
    }
}

fn detail(values: [Vec<i64>; 4], count: usize, width: usize, k: i64) -> String {
    let error = decode(&streams(&values), count, width, k, 0).unwrap_err();
    assert_eq!(error.rule, "R39-traversal");
    error.detail
}

/// Encodes `table`, decodes each corner order's streams: the input's rows in walk order.
fn round_trip(table: &[i64], width: usize, k: i64) {
    let walked = encode(table, width, k as u64).expect("a table the core takes");
    let count = table.len() / width;
    let mut expected = Vec::new();
    for &f in &walked.order {
        let f = f as usize;
        expected.extend_from_slice(&table[f * width..(f + 1) * width]);
    }
    for corner_order in 0..2 {
        let values = [
            walked.ops[corner_order].clone(),
            walked.degrees.clone(),
            walked.new_residuals.clone(),
            walked.references.clone(),
        ];
        let decoded = decode(&streams(&values), count, width, k, corner_order as i64).unwrap();
        assert_eq!(decoded, expected);
    }
}

#[test]
fn meshes_round_trip() {
    // a tetrahedron, an edge of four faces in both orientations, repeated corners, quads with
    // padding, two components and a vertex on no face
    round_trip(&[0, 1, 2, 0, 3, 1, 1, 3, 2, 2, 3, 0], 3, 4);
    round_trip(&[0, 1, 2, 1, 0, 3, 0, 1, 4, 1, 0, 5], 3, 6);
    round_trip(&[0, 1, 1, 1, 2, 2, 0, 0, 0, 2, 1, 0], 3, 3);
    round_trip(&[0, 1, 2, 3, 1, 4, 5, 2, 5, 4, 6, -1, 7, 8, 9, -1], 4, 11);
    round_trip(&[], 3, 0);
}

#[test]
fn a_fan_round_trips() {
    let mut table = Vec::new();
    for v in 2..2000 {
        table.extend_from_slice(if v % 2 == 0 { &[0, 1] } else { &[1, 0] });
        table.push(v);
    }
    round_trip(&table, 3, 2000);
}

#[test]
fn the_encoder_hands_back_what_it_does_not_take() {
    assert!(encode(&[0, 1, -1], 3, 3).is_none()); // a face of two corners
    assert!(encode(&[0, 1, 3], 3, 3).is_none()); // a vertex beyond k
    assert!(encode(&[0, 1, 2], 3, (1 << 32) + 1).is_none());
    assert!(encode(&[0, 1, 2, 3], 3, 4).is_none()); // not whole rows
}

#[test]
fn every_error_says_what_the_reference_says() {
    let seed = || vec![0, 0, 0];
    assert_eq!(
        detail([vec![], vec![], vec![], vec![]], 1, 3, 3),
        "a stream ends early"
    );
    assert_eq!(
        detail([seed(), vec![], vec![0, 0, 0, 0], vec![]], 1, 3, 4),
        "stream vertices has values left, or ends early"
    );
    assert_eq!(
        detail([seed(), vec![], vec![0, 0, 5], vec![]], 1, 3, 4),
        "new vertex 7 is outside 0..3 or placed"
    );
    assert_eq!(
        detail([seed(), vec![], vec![0, -1, 0], vec![]], 1, 3, 4),
        "new vertex 0 is outside 0..3 or placed"
    );
    assert_eq!(
        detail([vec![3, 0, 0], vec![], vec![0, 0], vec![5]], 1, 3, 4),
        "referenced vertex 5 is not one seen before"
    );
    assert_eq!(
        detail([vec![1, 0, 0], vec![], vec![0, 0], vec![]], 1, 3, 4),
        "tip operation 1 names no vertex here"
    );
    assert_eq!(
        detail([vec![0, 7, 0], vec![], vec![0, 0], vec![]], 1, 3, 4),
        "tip operation 7 names no vertex here"
    );
    // a second face across the seed's last gate: op outside 0..24, then a rotation of 3
    let gate = |op: i64| [vec![0, 0, 0, op], vec![], vec![0, 0, 0, 0], vec![]];
    assert_eq!(
        detail(gate(25), 2, 3, 5),
        "gate operation 25 is outside 0..24"
    );
    assert_eq!(
        detail(gate(-1), 2, 3, 5),
        "gate operation -1 is outside 0..24"
    );
    assert_eq!(
        detail(
            [vec![0, 0, 0, 25], vec![], vec![0, 0, 0, 0], vec![]],
            2,
            4,
            5
        ),
        "rotation 3 of a face of 3 corners"
    );
    assert_eq!(
        detail([seed(), vec![2], vec![0, 0, 0], vec![]], 1, 4, 4),
        "a face of 5 corners in a table of width 4"
    );
    assert_eq!(
        detail([seed(), vec![-1], vec![0, 0, 0], vec![]], 1, 4, 4),
        "a face of 2 corners in a table of width 4"
    );
    assert_eq!(
        detail(
            [vec![0, 0, 0], vec![], vec![0, 0, i64::MAX], vec![]],
            1,
            3,
            i64::MAX
        ),
        "new vertex 9223372036854775809 is outside 0..9223372036854775806 or placed"
    );
}

impl Random {
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }

    fn value(&mut self) -> i64 {
        match self.below(10) {
            0 => [i64::MIN, i64::MAX, i64::MIN + 1, i64::MAX - 1][self.below(4) as usize],
            1 => self.next() as i64,
            _ => self.below(30) as i64 - 4,
        }
    }

    fn stream(&mut self, most: u64) -> Vec<i64> {
        (0..self.below(most)).map(|_| self.value()).collect()
    }
}

#[test]
fn random_values_never_panic() {
    let mut random = Random(0x9E37_79B9_7F4A_7C15);
    for _ in 0..20_000 {
        let values = [
            random.stream(40),
            random.stream(6),
            random.stream(12),
            random.stream(8),
        ];
        let count = random.below(12) as usize;
        let width = random.below(7) as usize;
        let k = [0, 1, 5, 12, i64::MAX, -3][random.below(6) as usize];
        let _ = decode(&streams(&values), count, width, k, random.below(3) as i64);
    }
}
