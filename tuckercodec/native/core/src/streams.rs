//! Spec section 6.1, integer streams: zigzag integers split into byte planes.
//!
//! zstd stays in Python (the `zstandard` package); these functions are what comes after
//! decompression ([`unpack_planes`]) and before compression ([`pack_planes`]), the same bytes
//! and integers as `tuckercodec/format/streams.py`.

use crate::error::Broken;

/// The most byte planes a stream may hold (64-bit integers after zigzag; qmat sections allow
/// 4, section 6.9's integers 8).
pub const MAX_STORED_PLANES: usize = 8;

/// Signed to unsigned: 0, -1, 1, -2, 2 ... -> 0, 1, 2, 3, 4 ...
#[inline]
pub fn zigzag(value: i64) -> u64 {
    ((value << 1) ^ (value >> 63)) as u64
}

/// The inverse of [`zigzag`].
#[inline]
pub fn unzigzag(value: u64) -> i64 {
    ((value >> 1) as i64) ^ -((value & 1) as i64)
}

/// `count` signed integers from `planes` byte planes of `count` bytes each, least significant
/// plane first (`from_planes` then the unzigzag of `unpack_integers`).
///
/// This is the fuzzing entry point of the streams: any bytes are accepted; a length that is not
/// `count * planes`, or `planes` outside 1..=8, is an error (R29 / R30, which the Python side
/// has already ruled out before calling).
pub fn unpack_planes(raw: &[u8], count: usize, planes: usize) -> Result<Vec<i64>, Broken> {
    if !(1..=MAX_STORED_PLANES).contains(&planes) {
        return Err(Broken::new(
            "R30-planes",
            format!("planes must be 1..{MAX_STORED_PLANES}, got {planes}"),
        ));
    }
    let wanted = count.checked_mul(planes);
    if wanted != Some(raw.len()) {
        let shape = wanted.map_or_else(|| "more than can exist".to_string(), |n| n.to_string());
        return Err(Broken::new(
            "R29-zstd-content-size",
            format!("the zstd frame holds {} bytes, not {shape}", raw.len()),
        ));
    }
    let mut out = vec![0i64; count];
    unpack_planes_into(raw, planes, &mut out)?;
    Ok(out)
}

/// [`unpack_planes`] into `out`, whose length is the count (an array the caller allocated: numpy
/// backs a large one with huge pages, which a fresh `Vec` fills a page fault at a time).
pub fn unpack_planes_into(raw: &[u8], planes: usize, out: &mut [i64]) -> Result<(), Broken> {
    let count = out.len();
    if !(1..=MAX_STORED_PLANES).contains(&planes) {
        return Err(Broken::new(
            "R30-planes",
            format!("planes must be 1..{MAX_STORED_PLANES}, got {planes}"),
        ));
    }
    if count.checked_mul(planes) != Some(raw.len()) {
        return Err(Broken::new(
            "R29-zstd-content-size",
            format!(
                "the zstd frame holds {} bytes, not {}",
                raw.len(),
                count * planes
            ),
        ));
    }
    match planes {
        1 => gather::<1>(raw, out),
        2 => gather::<2>(raw, out),
        3 => gather::<3>(raw, out),
        4 => gather::<4>(raw, out),
        5 => gather::<5>(raw, out),
        6 => gather::<6>(raw, out),
        7 => gather::<7>(raw, out),
        _ => gather::<8>(raw, out),
    }
    Ok(())
}

/// Values handled at once by [`gather`] and [`scatter`]: a piece of every plane and of the
/// values, small enough to stay in the first-level cache.
const PIECE: usize = 4096;

/// The values of `PLANES` planes of `count` bytes (`raw` holds exactly them), unzigzagged: a
/// piece of the values at a time, each plane added to it in turn.
fn gather<const PLANES: usize>(raw: &[u8], out: &mut [i64]) {
    let count = out.len();
    let mut unsigned = [0u64; PIECE];
    for (index, piece) in out.chunks_mut(PIECE).enumerate() {
        let offset = index * PIECE;
        let unsigned = &mut unsigned[..piece.len()];
        unsigned.fill(0);
        for plane in 0..PLANES {
            let start = plane * count + offset;
            let bytes = &raw[start..start + piece.len()];
            for (value, &byte) in unsigned.iter_mut().zip(bytes) {
                *value |= u64::from(byte) << (8 * plane);
            }
        }
        for (out, &value) in piece.iter_mut().zip(unsigned.iter()) {
            *out = unzigzag(value);
        }
    }
}

/// The `PLANES` byte planes of `values` after zigzag: a piece of the values at a time, each
/// plane's bytes of it in turn.
fn scatter<const PLANES: usize>(values: &[i64]) -> Vec<u8> {
    let count = values.len();
    let mut out = vec![0u8; count * PLANES];
    for (index, piece) in values.chunks(PIECE).enumerate() {
        let offset = index * PIECE;
        for plane in 0..PLANES {
            let start = plane * count + offset;
            let bytes = &mut out[start..start + piece.len()];
            for (byte, &value) in bytes.iter_mut().zip(piece) {
                *byte = (zigzag(value) >> (8 * plane)) as u8;
            }
        }
    }
    out
}

/// `(planes, bytes)` of integers in stream order: zigzag, the fewest byte planes (at least 1)
/// that hold every value, then the planes, least significant first (`zigzag`, `planes_needed`
/// and `to_planes` of `pack_integers`). `planes` may exceed 4: the caller refuses that.
pub fn pack_planes(values: &[i64]) -> (usize, Vec<u8>) {
    let largest = values.iter().map(|&v| zigzag(v)).max().unwrap_or(0);
    let bits = 64 - largest.leading_zeros() as usize;
    let planes = bits.div_ceil(8).max(1);
    let raw = match planes {
        1 => scatter::<1>(values),
        2 => scatter::<2>(values),
        3 => scatter::<3>(values),
        4 => scatter::<4>(values),
        5 => scatter::<5>(values),
        6 => scatter::<6>(values),
        7 => scatter::<7>(values),
        _ => scatter::<8>(values),
    };
    (planes, raw)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zigzag_order_and_inverse() {
        let values = [0i64, -1, 1, -2, 2, i64::MAX, i64::MIN, -(1 << 31), 1 << 31];
        let expected = [
            0u64,
            1,
            2,
            3,
            4,
            u64::MAX - 1,
            u64::MAX,
            (1 << 32) - 1,
            1 << 32,
        ];
        for (&v, &z) in values.iter().zip(&expected) {
            assert_eq!(zigzag(v), z);
            assert_eq!(unzigzag(z), v);
        }
    }

    #[test]
    fn planes_round_trip() {
        let values = [0i64, 5, -300, 70000, -(1 << 31), i64::MIN, i64::MAX];
        for slice in [
            &values[..0],
            &values[..2],
            &values[..4],
            &values[..5],
            &values[..],
        ] {
            let (planes, raw) = pack_planes(slice);
            assert_eq!(raw.len(), slice.len() * planes);
            assert_eq!(unpack_planes(&raw, slice.len(), planes).unwrap(), slice);
        }
        assert_eq!(pack_planes(&[]).0, 1);
        assert_eq!(pack_planes(&[-128, 127]).0, 1);
        assert_eq!(pack_planes(&[128]).0, 2);
        assert_eq!(pack_planes(&[i64::MIN]).0, 8);
    }

    #[test]
    fn plane_layout_is_least_significant_first() {
        let (planes, raw) = pack_planes(&[1, -129]);
        assert_eq!(planes, 2);
        // zigzag: 2 and 257 = 0x101
        assert_eq!(raw, vec![2, 1, 0, 1]);
    }

    #[test]
    fn wrong_lengths_are_errors() {
        assert_eq!(
            unpack_planes(&[1, 2, 3], 2, 2).unwrap_err().rule,
            "R29-zstd-content-size"
        );
        assert_eq!(unpack_planes(&[], 0, 0).unwrap_err().rule, "R30-planes");
        assert_eq!(unpack_planes(&[], 0, 9).unwrap_err().rule, "R30-planes");
        assert!(unpack_planes(&[0; 3], usize::MAX, 2).is_err());
        assert_eq!(unpack_planes(&[], 0, 3).unwrap(), Vec::<i64>::new());
    }
}
