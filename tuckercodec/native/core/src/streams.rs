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
    let mut out = vec![0u64; count];
    for (plane, bytes) in raw.chunks_exact(count.max(1)).enumerate().take(planes) {
        let shift = 8 * plane as u32;
        for (value, &byte) in out.iter_mut().zip(bytes) {
            *value |= u64::from(byte) << shift;
        }
    }
    Ok(out.into_iter().map(unzigzag).collect())
}

/// `(planes, bytes)` of integers in stream order: zigzag, the fewest byte planes (at least 1)
/// that hold every value, then the planes, least significant first (`zigzag`, `planes_needed`
/// and `to_planes` of `pack_integers`). `planes` may exceed 4: the caller refuses that.
pub fn pack_planes(values: &[i64]) -> (usize, Vec<u8>) {
    let largest = values.iter().map(|&v| zigzag(v)).max().unwrap_or(0);
    let bits = 64 - largest.leading_zeros() as usize;
    let planes = bits.div_ceil(8).max(1);
    let count = values.len();
    let mut out = vec![0u8; count * planes];
    for (plane, bytes) in out.chunks_exact_mut(count.max(1)).enumerate().take(planes) {
        let shift = 8 * plane as u32;
        for (byte, &value) in bytes.iter_mut().zip(values) {
            *byte = (zigzag(value) >> shift) as u8;
        }
    }
    (planes, out)
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
