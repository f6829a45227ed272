//! Uniform streams (format 1.9, §6.8): integers each spread evenly over a range the decoder
//! knows, as truncated binary in the direct bits of §6.14's range coder. `encode_uniform` and
//! `decode_uniform` of `tuckercodec/format/uniform.py`, bit for bit.
//!
//! The i-th integer (from 0) of a stream over `total` lies in `0..total - i - 1`. With
//! n = total - i, k = floor(log2 n) and u = 2**(k + 1) - n, a value below u is its k bits, any
//! other the k + 1 bits of value + u.

use super::coder::{RangeDecoder, RangeEncoder};
use super::{check_size, RULE};
use crate::error::Broken;

/// The largest `total` of a uniform stream: its integers are 32-bit ones.
pub const MAX_TOTAL: u64 = 1 << 31;

/// `(k, u)` of a value in `0..n` (n >= 1): its short length and the count of short values.
fn sizes(n: u64) -> (u32, u64) {
    let k = 63 - n.leading_zeros();
    (k, (2_u64 << k) - n)
}

/// The uniform stream of `values` over `total`: an error naming the first value outside its
/// range (the caller's mistake, not a file's), or more values than `total`.
pub fn encode_uniform(values: &[i64], total: u64) -> Result<Vec<u8>, String> {
    if total > MAX_TOTAL || values.len() as u64 > total {
        return Err(format!(
            "{} values over {total} do not make a uniform stream",
            values.len()
        ));
    }
    let mut coder = RangeEncoder::new();
    for (i, &value) in values.iter().enumerate() {
        let n = total - i as u64;
        let value = u64::try_from(value)
            .ok()
            .filter(|&v| v < n)
            .ok_or_else(|| format!("value {i} is {value}, outside 0..{}", n - 1))?;
        let (k, u) = sizes(n);
        let (code, length) = if value < u {
            (value, k)
        } else {
            (value + u, k + 1)
        };
        for shift in (0..length).rev() {
            coder.direct((code >> shift) & 1 == 1);
        }
    }
    Ok(coder.finish())
}

/// The `count` integers of the uniform stream `payload` over `total`; R46 for a payload that is
/// not exactly their coding (its start and end as §6.14's), or for a `count` above `total` or
/// the payload's bound.
pub fn decode_uniform(payload: &[u8], count: usize, total: u64) -> Result<Vec<i64>, Broken> {
    check_size(1, count, payload.len())?;
    if total > MAX_TOTAL || count as u64 > total {
        return Err(Broken::new(
            RULE,
            format!("{count} values cannot be chosen among {total}"),
        ));
    }
    let mut coder = RangeDecoder::new(payload)?;
    let mut out = Vec::with_capacity(count);
    for i in 0..count as u64 {
        let (k, u) = sizes(total - i);
        let mut value = 0_u64;
        for _ in 0..k {
            value = (value << 1) | u64::from(coder.direct());
        }
        if value >= u {
            value = ((value << 1) | u64::from(coder.direct())) - u;
        }
        // below total <= 2**31
        out.push(value as i64);
    }
    coder.finish()?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_random::Random;

    #[test]
    fn values_come_back_and_short_ones_take_k_bits() {
        let mut random = Random(5);
        for total in [1_u64, 2, 3, 5, 8, 100, 1000, 4097] {
            let count = (total as usize).min(700);
            let values: Vec<i64> = (0..count as u64)
                .map(|i| (random.next() % (total - i)) as i64)
                .collect();
            let payload = encode_uniform(&values, total).unwrap();
            assert_eq!(decode_uniform(&payload, count, total).unwrap(), values);
        }
        assert_eq!(sizes(1), (0, 1));
        assert_eq!(sizes(5), (2, 3));
        assert_eq!(sizes(8), (3, 8));
    }

    #[test]
    fn every_value_of_the_range_and_no_other() {
        for n in 1..40_u64 {
            for value in 0..n as i64 {
                let payload = encode_uniform(&[value], n).unwrap();
                assert_eq!(decode_uniform(&payload, 1, n).unwrap(), vec![value]);
            }
            assert!(encode_uniform(&[n as i64], n).is_err());
            assert!(encode_uniform(&[-1], n).is_err());
        }
    }

    #[test]
    fn damaged_streams_are_r46() {
        let values: Vec<i64> = (0..50).map(|i| (i * 7) % (100 - i)).collect();
        let payload = encode_uniform(&values, 100).unwrap();
        let short = &payload[..payload.len() - 1];
        assert_eq!(decode_uniform(short, 50, 100).unwrap_err().rule, RULE);
        let mut long = payload.clone();
        long.push(0);
        assert_eq!(decode_uniform(&long, 50, 100).unwrap_err().rule, RULE);
        assert_eq!(decode_uniform(&payload, 101, 100).unwrap_err().rule, RULE);
        assert!(decode_uniform(&payload, 50, MAX_TOTAL + 1).is_err());
    }
}
