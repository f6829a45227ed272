//! §6.9's codebooks (format 1.8): on an axis whose values are few, a section stores each value
//! as a difference of positions in the sorted list of its ordered integers. These are the
//! reference's `nearest_entries` and `from_codebooks` (in `format/residual.py`) for one axis:
//! the same integers, each found through an index of the codebook's midpoints by value.

use crate::error::Broken;
use crate::residual::{ordered_in, Domain, VALUE_RULE};

/// j of §6.9 for each ordered integer of `base`, written to `out`: how many of `middles` lie
/// below it, where `middles` are the codebook's midpoints (increasing; the reference's
/// `midpoints`), so that j is the entry nearest it, the lower on a tie.
pub fn nearest_entries(middles: &[i64], base: &[i64], out: &mut [usize]) {
    if base.len() < middles.len() / INDEXED_SHARE {
        // a frame or two of a large codebook: the index would cost more to make than it saves
        // (chicken's one frame 1.6 -> 2.4 ms), and a binary search each is the same count
        for (value, slot) in base.iter().zip(out.iter_mut()) {
            *slot = middles.partition_point(|m| *m < *value);
        }
        return;
    }
    let index = MiddleIndex::new(middles);
    for (value, slot) in base.iter().zip(out.iter_mut()) {
        *slot = index.count_below(*value);
    }
}

/// [`nearest_entries`] makes a [`MiddleIndex`] for at least one value per this many midpoints.
const INDEXED_SHARE: usize = 4;

/// The codebook's midpoints cut into about as many equal ranges of values as there are
/// midpoints, with the number of midpoints below each range's start: a value's count is then
/// one lookup and a search among the few midpoints of its range. (A search outwards from the
/// vertex's entry in the frames before took 60 ns a value on horse-gallop's codebooks of
/// 200,000 entries, where a gallop moves a vertex far between frames; this takes 14.)
pub struct MiddleIndex<'a> {
    middles: &'a [i64],
    /// The first midpoint; a value at or below it has none below.
    low: i64,
    /// The last midpoint's distance from the first.
    span: u64,
    /// A value's range is its distance from `low` shifted right by this.
    shift: u32,
    /// `starts[k]`: how many midpoints lie in the ranges before range k (one more entry than
    /// ranges).
    starts: Vec<usize>,
}

impl<'a> MiddleIndex<'a> {
    /// The index of `middles` (increasing).
    pub fn new(middles: &'a [i64]) -> Self {
        let (Some(&low), Some(&high)) = (middles.first(), middles.last()) else {
            return MiddleIndex {
                middles,
                low: 0,
                span: 0,
                shift: 0,
                starts: vec![0, 0],
            };
        };
        // high >= low: the difference fits 64 bits unsigned
        let span = high.wrapping_sub(low) as u64;
        let wanted = usize::BITS - middles.len().leading_zeros(); // ranges: about 2**wanted
        let shift = (u64::BITS - span.leading_zeros()).saturating_sub(wanted);
        let ranges = (span >> shift) as usize + 1; // at most 2**(wanted + 1)
        let mut starts = vec![0_usize; ranges + 1];
        for &m in middles {
            starts[Self::range(m.wrapping_sub(low) as u64, shift) + 1] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        MiddleIndex {
            middles,
            low,
            span,
            shift,
            starts,
        }
    }

    #[inline(always)]
    fn range(distance: u64, shift: u32) -> usize {
        (distance >> shift) as usize
    }

    /// How many midpoints are below `value`. Within a range the midpoints of earlier ranges
    /// are all below it and those of later ones all above: (a >> s) < (b >> s) implies a < b.
    #[inline]
    pub fn count_below(&self, value: i64) -> usize {
        if value <= self.low {
            return 0;
        }
        let distance = value.wrapping_sub(self.low) as u64; // value > low
        if distance > self.span {
            return self.middles.len();
        }
        let k = Self::range(distance, self.shift);
        let (first, end) = (self.starts[k], self.starts[k + 1]);
        first + self.middles[first..end].partition_point(|m| *m < value)
    }
}

/// The corrections e of `domain` that `stored` (positions in `book` less the nearest entry's,
/// §6.9) mean for the positions `exact` of one axis,
/// written to `out`: `C[j + s] - b`, so that correcting P by e gives `C[j + s]`'s value. A P
/// that is not finite (outside `float32`) gets 0: its position is not finite whatever e is
/// (R36). R41 when `j + s` is outside the codebook; `middles` are the codebook's midpoints.
pub fn codebook_corrections(
    exact: &[f64],
    stored: &[i64],
    domain: Domain,
    book: &[i64],
    middles: &[i64],
    out: &mut [i64],
) -> Result<(), Broken> {
    let count = exact.len();
    if stored.len() != count || out.len() != count || middles.len() + 1 != book.len() {
        return Err(Broken::new(
            VALUE_RULE,
            format!(
                "{count} positions, {} integers, {} outputs, a codebook of {} and {} midpoints",
                stored.len(),
                out.len(),
                book.len(),
                middles.len()
            ),
        ));
    }
    let skips_infinite = domain != Domain::Float32;
    let finite: Vec<f64> = exact
        .iter()
        .map(|p| {
            if skips_infinite && !p.is_finite() {
                0.0
            } else {
                *p
            }
        })
        .collect();
    let mut base = vec![0_i64; count];
    ordered_in(&finite, domain, &mut base);
    let mut nearest = vec![0_usize; count];
    nearest_entries(middles, &base, &mut nearest);
    let last = book.len() - 1; // book.len() >= 1: middles.len() + 1
    for index in 0..count {
        if skips_infinite && !exact[index].is_finite() {
            out[index] = 0;
            continue;
        }
        let position = i128::from(stored[index]) + nearest[index] as i128;
        if position < 0 || position > last as i128 {
            return Err(Broken::new(
                VALUE_RULE,
                format!(
                    "a correction moves beyond a codebook of {} entries",
                    book.len()
                ),
            ));
        }
        out[index] = book[position as usize].wrapping_sub(base[index]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_random::Random;

    fn midpoints(book: &[i64]) -> Vec<i64> {
        book.windows(2)
            .map(|pair| ((i128::from(pair[0]) + i128::from(pair[1])).div_euclid(2)) as i64)
            .collect()
    }

    fn nearest_by_definition(book: &[i64], value: i64) -> usize {
        // §6.9 word for word, in 128-bit integers
        let below = book.iter().rposition(|c| *c <= value).unwrap_or(0);
        let (b, low) = (i128::from(value), i128::from(book[below]));
        let up = below + 1 < book.len() && low <= b && i128::from(book[below + 1]) - b < b - low;
        below + usize::from(up)
    }

    fn nearest_of(book: &[i64], values: &[i64]) -> Vec<usize> {
        let mut found = vec![0; values.len()];
        nearest_entries(&midpoints(book), values, &mut found);
        found
    }

    #[test]
    fn the_index_finds_the_definitions_nearest_entry() {
        let mut random = Random(7);
        let mut book: Vec<i64> = (0..300).map(|_| random.next() as i64).collect();
        book.extend([i64::MIN + 5, i64::MAX - 5, -1, 0, 1]);
        book.sort_unstable();
        book.dedup();
        let middles = midpoints(&book);
        let values: Vec<i64> = (0..4000)
            .map(|round| match round % 4 {
                0 => random.next() as i64,
                1 => book[(random.next() % book.len() as u64) as usize],
                2 => middles[(random.next() % middles.len() as u64) as usize] + 1,
                _ => book[(random.next() % book.len() as u64) as usize].wrapping_sub(1),
            })
            .collect();
        for (value, j) in values.iter().zip(nearest_of(&book, &values)) {
            assert_eq!(j, nearest_by_definition(&book, *value), "value {value}");
        }
    }

    #[test]
    fn a_few_values_searched_without_the_index_give_the_definitions_entry() {
        let mut random = Random(13);
        let mut book: Vec<i64> = (0..4000).map(|_| random.next() as i64).collect();
        book.extend([i64::MIN, i64::MAX]);
        book.sort_unstable();
        book.dedup();
        let values: Vec<i64> = (0..50)
            .map(|round| match round % 3 {
                0 => random.next() as i64,
                1 => book[(random.next() % book.len() as u64) as usize],
                _ => midpoints(&book)[(random.next() % (book.len() as u64 - 1)) as usize] + 1,
            })
            .collect();
        assert!(values.len() < (book.len() - 1) / INDEXED_SHARE);
        for (value, j) in values.iter().zip(nearest_of(&book, &values)) {
            assert_eq!(j, nearest_by_definition(&book, *value), "value {value}");
        }
    }

    #[test]
    fn clustered_books_and_every_span_give_the_definitions_entry() {
        let mut random = Random(11);
        // entries crowded into a few narrow ranges far apart (a mesh's few parts), the widest
        // span there is, one entry, two entries, and neighbours one apart
        let crowded: Vec<i64> = (0..600)
            .map(|n| [-(1_i64 << 40), 17, 1 << 50][n % 3] + (n as i64) * 3)
            .collect();
        let books: [Vec<i64>; 5] = [
            crowded,
            vec![i64::MIN, -1, 0, i64::MAX],
            vec![42],
            vec![-5, 5],
            (-50..50).collect(),
        ];
        for mut book in books {
            book.sort_unstable();
            book.dedup();
            let mut values = vec![i64::MIN, i64::MAX, 0, -1, 1];
            for &entry in &book {
                values.extend([entry, entry.wrapping_sub(1), entry.wrapping_add(1)]);
            }
            values.extend((0..2000).map(|_| {
                let entry = book[(random.next() % book.len() as u64) as usize];
                entry.wrapping_add((random.next() % 64) as i64 - 32)
            }));
            for (value, j) in values.iter().zip(nearest_of(&book, &values)) {
                assert_eq!(j, nearest_by_definition(&book, *value), "value {value}");
            }
        }
    }

    #[test]
    fn stored_positions_become_the_codebook_values_and_leaving_it_is_r41() {
        let book = [1_i64, 5, 9];
        let middles = midpoints(&book);
        let exact = [0.0_f64, 4.0, 9.0, f64::NAN];
        let stored = [2_i64, 0, -1, 99];
        let mut out = [0_i64; 4];
        codebook_corrections(&exact, &stored, Domain::Float64, &book, &middles, &mut out).unwrap();
        let base: Vec<i64> = exact[..3]
            .iter()
            .map(|v| crate::residual::ordered64(*v))
            .collect();
        assert_eq!(out[..3], [9 - base[0], 9 - base[1], 5 - base[2]]);
        assert_eq!(out[3], 0); // not finite: R36, whatever is stored
        let beyond = [0_i64, 0, 1, 0];
        let error =
            codebook_corrections(&exact, &beyond, Domain::Float64, &book, &middles, &mut out)
                .unwrap_err();
        assert_eq!(error.rule, VALUE_RULE);
        let far = [i64::MIN, 0, 0, 0];
        assert!(
            codebook_corrections(&exact, &far, Domain::Float64, &book, &middles, &mut out).is_err()
        );
    }
}
