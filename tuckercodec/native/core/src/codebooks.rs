//! §6.9's codebooks (format 1.8): on an axis whose values are few, a section stores each value
//! as a difference of positions in the sorted list of its ordered integers. These are the
//! reference's `nearest_entries` and `from_codebooks` (in `format/residual.py`) for one axis:
//! the same integers, found faster by starting each search where the same vertex's ended in
//! the frame before, as values move little from one frame to the next.

use crate::error::Broken;
use crate::residual::{ordered_in, Domain, VALUE_RULE};

/// j of §6.9 for each ordered integer of `base` (an axis's values, frame-major, `frame_values`
/// to a frame), written to `out`: how many of `middles` lie below it, where `middles` are the
/// codebook's midpoints (increasing; the reference's `midpoints`), so that j is the entry
/// nearest it, the lower on a tie.
pub fn nearest_entries(middles: &[i64], base: &[i64], frame_values: usize, out: &mut [usize]) {
    let first = middles.len() / 2;
    for index in 0..base.len().min(out.len()) {
        let hint = if frame_values > 0 && index >= 2 * frame_values {
            // where the same vertex's entry would be had it kept moving as in the two frames
            // before (on chicken, half the distance of the last frame's alone)
            let (last, before) = (out[index - frame_values], out[index - 2 * frame_values]);
            (2 * last).saturating_sub(before)
        } else if frame_values > 0 && index >= frame_values {
            out[index - frame_values] // the same vertex a frame before: usually near
        } else {
            first
        };
        out[index] = count_below(middles, base[index], hint);
    }
}

/// How many of `middles` (increasing) are below `value`, searched from `hint`: outwards in
/// steps that double, then by halves (an exponential search: a few comparisons when the
/// answer is near the hint, never much more than a binary search's).
pub fn count_below(middles: &[i64], value: i64, hint: usize) -> usize {
    let count = middles.len();
    let hint = hint.min(count);
    if hint < count && middles[hint] < value {
        // everything up to the hint is below: look above it
        let mut low = hint + 1;
        let mut step = 1;
        loop {
            let probe = low + step;
            if probe > count {
                return low + middles[low..].partition_point(|m| *m < value);
            }
            if middles[probe - 1] < value {
                low = probe;
                step *= 2;
            } else {
                return low + middles[low..probe - 1].partition_point(|m| *m < value);
            }
        }
    }
    // everything from the hint on is at or above: look below it
    let mut high = hint;
    let mut step = 1;
    loop {
        if step > high {
            return middles[..high].partition_point(|m| *m < value);
        }
        let probe = high - step;
        if middles[probe] >= value {
            high = probe;
            step *= 2;
        } else {
            return probe + 1 + middles[probe + 1..high].partition_point(|m| *m < value);
        }
    }
}

/// The corrections e of `domain` that `stored` (positions in `book` less the nearest entry's,
/// §6.9) mean for the positions `exact` of one axis (frame-major, `frame_values` to a frame),
/// written to `out`: `C[j + s] - b`, so that correcting P by e gives `C[j + s]`'s value. A P
/// that is not finite (outside `float32`) gets 0: its position is not finite whatever e is
/// (R36). R41 when `j + s` is outside the codebook; `middles` are the codebook's midpoints.
pub fn codebook_corrections(
    exact: &[f64],
    stored: &[i64],
    domain: Domain,
    book: &[i64],
    middles: &[i64],
    frame_values: usize,
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
    nearest_entries(middles, &base, frame_values, &mut nearest);
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

    #[test]
    fn the_search_from_any_hint_is_the_definitions_nearest_entry() {
        let mut random = Random(7);
        let mut book: Vec<i64> = (0..300).map(|_| random.next() as i64).collect();
        book.extend([i64::MIN + 5, i64::MAX - 5, -1, 0, 1]);
        book.sort_unstable();
        book.dedup();
        let middles = midpoints(&book);
        for round in 0..4000 {
            let value = match round % 4 {
                0 => random.next() as i64,
                1 => book[(random.next() % book.len() as u64) as usize],
                2 => middles[(random.next() % middles.len() as u64) as usize] + 1,
                _ => book[(random.next() % book.len() as u64) as usize].wrapping_sub(1),
            };
            let hint = (random.next() % (book.len() as u64 + 3)) as usize;
            assert_eq!(
                count_below(&middles, value, hint),
                nearest_by_definition(&book, value),
                "value {value}, hint {hint}"
            );
        }
    }

    #[test]
    fn frames_searched_from_the_frame_before_give_the_same_entries() {
        let mut random = Random(11);
        let book: Vec<i64> = (0..50).map(|n| n * 10 + (n % 3)).collect();
        let middles = midpoints(&book);
        let base: Vec<i64> = (0..6 * 40)
            .map(|_| (random.next() % 600) as i64 - 50)
            .collect();
        let mut found = vec![0; base.len()];
        nearest_entries(&middles, &base, 40, &mut found);
        for (value, j) in base.iter().zip(&found) {
            assert_eq!(*j, nearest_by_definition(&book, *value));
        }
    }

    #[test]
    fn stored_positions_become_the_codebook_values_and_leaving_it_is_r41() {
        let book = [1_i64, 5, 9];
        let middles = midpoints(&book);
        let exact = [0.0_f64, 4.0, 9.0, f64::NAN];
        let stored = [2_i64, 0, -1, 99];
        let mut out = [0_i64; 4];
        codebook_corrections(
            &exact,
            &stored,
            Domain::Float64,
            &book,
            &middles,
            4,
            &mut out,
        )
        .unwrap();
        let base: Vec<i64> = exact[..3]
            .iter()
            .map(|v| crate::residual::ordered64(*v))
            .collect();
        assert_eq!(out[..3], [9 - base[0], 9 - base[1], 5 - base[2]]);
        assert_eq!(out[3], 0); // not finite: R36, whatever is stored
        let beyond = [0_i64, 0, 1, 0];
        let error = codebook_corrections(
            &exact,
            &beyond,
            Domain::Float64,
            &book,
            &middles,
            4,
            &mut out,
        )
        .unwrap_err();
        assert_eq!(error.rule, VALUE_RULE);
        let far = [i64::MIN, 0, 0, 0];
        assert!(
            codebook_corrections(&exact, &far, Domain::Float64, &book, &middles, 4, &mut out)
                .is_err()
        );
    }
}
