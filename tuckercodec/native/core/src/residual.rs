//! §6.9 codec `residual`: the corrections of error-bounded and lossless files.
//!
//! The port of the per-value loops of `tuckercodec/format/residual.py`: a chunk's integers
//! restored from its decompressed byte planes ([`restore_chunk`]), the maps between values and
//! the ordered integers of each domain ([`ordered32`], [`ordered64`], [`places_ordered`],
//! [`digits_ordered`] and their inverses), and the correction of §8.1's exact positions by
//! those integers ([`correct`], the R41 checks in the reference's order). The zstd frame
//! itself is decompressed by the caller (R29 is checked there).
//!
//! Every function takes plain slices and returns a [`Broken`] for any input it refuses, never
//! a panic, so a fuzzer may call them with anything. The entry points meant for it:
//!
//! - [`restore_chunk`]`(raw, count, planes, predict, frame_values)`: any bytes and sizes; the
//!   integers, or R29 for a shape the bytes do not hold;
//! - [`correct`]`(exact, residual, domain, out)`: any positions and integers in any
//!   [`Domain`] (from [`Domain::named`], or built directly: a grid's step is then whatever
//!   the fuzzer gives); the corrected positions, or R41 with the reference's message;
//! - [`pack_chunk`] then [`restore_chunk`]: a round trip that must give the integers back;
//! - [`ordered_in`] then [`correct`] with zero corrections: a lossless domain's values back.

use crate::error::Broken;
use crate::streams::{unzigzag, zigzag};

/// The rule every correction check reports (spec section 11).
pub const VALUE_RULE: &str = "R41-residual-value";
/// The rule a chunk whose bytes do not match its shape breaks (its zstd frame, §6.1 step 3).
pub const CHUNK_RULE: &str = "R29-zstd-content-size";
/// The most byte planes of a chunk (64-bit integers).
pub const MAX_PLANES: usize = 8;

/// Integers restored at once by [`restore_chunk`] (16 KiB of scratch).
const RESTORE_BLOCK: usize = 2048;

/// The ordered integers of the finite binary32 values: -max and +max.
pub const FINITE32: (i64, i64) = (-2_139_095_040, 2_139_095_039);
/// The ordered integers of the finite binary64 values: -max and +max.
pub const FINITE64: (i64, i64) = (-9_218_868_437_227_405_312, 9_218_868_437_227_405_311);
/// |e| allowed in domain `grid` (binary64 widens it exactly).
pub const GRID_LARGEST: i64 = 1 << 53;
/// |e| allowed in domain `float32`.
pub const FLOAT32_LARGEST: i64 = 1 << 32;
/// The largest |k| of domain `decimal-places`.
pub const LARGEST_PLACES_INTEGER: i64 = 1 << 53;

/// 10**n for n = 0..22, each exact in binary64.
pub const TEN: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// How integers correct values (§6.9): a grid of spacing `step`, the ordered integers of
/// binary32 or binary64 values, or decimals of `places` places or `digits` significant digits
/// (as binary64, or rounded once more to binary32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Domain {
    /// `grid`: P + step * e.
    Grid { step: f64 },
    /// `float32`: the binary32 nearest P, moved by e on the ordered integers.
    Float32,
    /// `float64`: P moved by e on the ordered integers of binary64.
    Float64,
    /// `decimal-places`: k / 10**places, places in 0..=22.
    Places { places: u32 },
    /// `decimal-digits`: decimals of `digits` (1..=15) significant digits.
    Digits { digits: u32 },
    /// `decimal-digits-float32`: those decimals rounded to binary32.
    Digits32 { digits: u32 },
}

impl Domain {
    /// The domain of a section's parameters as the Python reference names it (`"grid"`,
    /// `"float32"`, `"float64"`, `"decimal-places"`, `"decimal-digits"`,
    /// `"decimal-digits-float32"`), with the grid's step or the decimals' places or digits;
    /// `None` for a name or a scale out of §6.9's range (R40 is the caller's to report).
    pub fn named(name: &str, step: f64, scale: i64) -> Option<Domain> {
        let places = u32::try_from(scale).ok().filter(|p| *p <= 22);
        let digits = u32::try_from(scale).ok().filter(|d| (1..=15).contains(d));
        match name {
            "grid" => (step.is_finite() && step > 0.0).then_some(Domain::Grid { step }),
            "float32" => Some(Domain::Float32),
            "float64" => Some(Domain::Float64),
            "decimal-places" => places.map(|places| Domain::Places { places }),
            "decimal-digits" => digits.map(|digits| Domain::Digits { digits }),
            "decimal-digits-float32" => digits.map(|digits| Domain::Digits32 { digits }),
            _ => None,
        }
    }
}

fn value_error(detail: impl Into<String>) -> Broken {
    Broken::new(VALUE_RULE, detail)
}

// -- a chunk's integers (§6.9 "Chunks" and "Restoring e") -----------------------------------

/// The restored integers e of one chunk, in stream order (frame, vertex, axis): `count`
/// 64-bit zigzagged integers in `planes` byte planes (least significant first, plane-major)
/// read from `raw`, the chunk's decompressed zstd frame; with `predict`, each frame of
/// `frame_values` integers summed with the one before it (64-bit addition that wraps).
///
/// Refuses (R29) a `raw` that is not `count * planes` bytes, and a `planes` out of 1..=8 or a
/// `frame_values` that does not divide `count` (which the reference's layout never gives).
pub fn restore_chunk(
    raw: &[u8],
    count: usize,
    planes: usize,
    predict: bool,
    frame_values: usize,
) -> Result<Vec<i64>, Broken> {
    if !(1..=MAX_PLANES).contains(&planes) {
        return Err(Broken::new(
            CHUNK_RULE,
            format!("a chunk has 1..{MAX_PLANES} planes, got {planes}"),
        ));
    }
    let size = count.checked_mul(planes);
    if size != Some(raw.len()) {
        let wanted = size.map_or_else(|| "more".to_string(), |s| s.to_string());
        return Err(Broken::new(
            CHUNK_RULE,
            format!("the zstd frame holds {} bytes, not {wanted}", raw.len()),
        ));
    }
    if count > 0 && (frame_values == 0 || count % frame_values != 0) {
        return Err(Broken::new(
            CHUNK_RULE,
            format!("{count} integers are not whole frames of {frame_values}"),
        ));
    }
    // one pass over the output, a block at a time: each plane's bytes of the block gathered
    // while the block stays in cache, then unzigzagged and summed with the frame before
    let mut values = vec![0i64; count];
    let mut block = [0u64; RESTORE_BLOCK];
    for first in (0..count).step_by(RESTORE_BLOCK) {
        let length = RESTORE_BLOCK.min(count - first);
        let unsigned = &mut block[..length];
        unsigned.fill(0);
        for plane in 0..planes {
            let bytes = &raw[plane * count + first..plane * count + first + length];
            let shift = 8 * plane as u32;
            for (value, byte) in unsigned.iter_mut().zip(bytes) {
                *value |= u64::from(*byte) << shift;
            }
        }
        for (offset, value) in unsigned.iter().enumerate() {
            let index = first + offset;
            let restored = unzigzag(*value);
            values[index] = if predict && index >= frame_values {
                restored.wrapping_add(values[index - frame_values]) // e[t] = s[t] + e[t - 1]
            } else {
                restored
            };
        }
    }
    Ok(values)
}

/// A chunk's integers packed as §6.9 stores them, before zstd: with `predict`, each frame of
/// `frame_values` integers less the one before it (wrapping), zigzagged, then the fewest byte
/// planes (at least 1) that hold them, least significant plane first. Returns the planes and
/// the bytes. Refuses (R29) a `frame_values` that does not divide the values.
pub fn pack_chunk(
    values: &[i64],
    predict: bool,
    frame_values: usize,
) -> Result<(usize, Vec<u8>), Broken> {
    let count = values.len();
    if count > 0 && (frame_values == 0 || count % frame_values != 0) {
        return Err(Broken::new(
            CHUNK_RULE,
            format!("{count} integers are not whole frames of {frame_values}"),
        ));
    }
    let unsigned: Vec<u64> = values
        .iter()
        .enumerate()
        .map(|(index, value)| {
            if predict && index >= frame_values {
                zigzag(value.wrapping_sub(values[index - frame_values]))
            } else {
                zigzag(*value)
            }
        })
        .collect();
    let largest = unsigned.iter().copied().max().unwrap_or(0);
    let bits = 64 - largest.leading_zeros() as usize;
    let planes = bits.div_ceil(8).max(1);
    let mut raw = vec![0u8; count * planes];
    // a block of values at a time, each plane's bytes of it written while it is in cache
    for first in (0..count).step_by(RESTORE_BLOCK) {
        let block = &unsigned[first..count.min(first + RESTORE_BLOCK)];
        for plane in 0..planes {
            let start = plane * count + first;
            let shift = 8 * plane as u32;
            for (byte, value) in raw[start..start + block.len()].iter_mut().zip(block) {
                *byte = (value >> shift) as u8;
            }
        }
    }
    Ok((planes, raw))
}

/// The integer nearest `value`, ties to even, as `f64::round_ties_even` (and numpy's `rint`)
/// gives it, without the call to libm's `rint` that the baseline x86-64 target makes of it:
/// below 2**52 in magnitude, adding and subtracting 2**52 rounds so (each sum rounded to
/// nearest, ties to even); above it every binary64 is an integer already.
#[inline]
pub fn rint(value: f64) -> f64 {
    const TWO52: f64 = 4_503_599_627_370_496.0;
    let magnitude = value.abs();
    if magnitude < TWO52 {
        // the sign kept, so that -0.4 is -0, as rint gives it
        ((magnitude + TWO52) - TWO52).copysign(value)
    } else {
        value // an integer, an infinity or a NaN
    }
}

// -- the ordered integers (§6.9) --------------------------------------------------------------

/// The ordered integer of a binary32 value.
pub fn ordered32(value: f32) -> i64 {
    let bits = i64::from(value.to_bits() as i32);
    if bits >= 0 {
        bits
    } else {
        -(1i64 << 31) - bits - 1
    }
}

/// The binary32 value of an ordered integer within [`FINITE32`] (outside it, the low 32 bits
/// of the map, as the reference's cast gives).
pub fn from_ordered32(ordered: i64) -> f32 {
    let bits = if ordered >= 0 {
        ordered
    } else {
        (-(1i64 << 31)).wrapping_sub(ordered).wrapping_sub(1)
    };
    f32::from_bits(bits as i32 as u32)
}

/// The ordered integer of a binary64 value.
pub fn ordered64(value: f64) -> i64 {
    let bits = value.to_bits() as i64;
    if bits >= 0 {
        bits
    } else {
        !bits ^ i64::MIN
    }
}

/// The binary64 value of an ordered integer (the map is its own inverse).
pub fn from_ordered64(ordered: i64) -> f64 {
    f64::from_bits(ordered64(f64::from_bits(ordered as u64)) as u64)
}

// -- decimals (§6.9) ----------------------------------------------------------------------------

/// k, the integer nearest value * 10**places (one binary64 product, rounded half to even),
/// within +-2**53 (a NaN is 0, as the reference's `nan_to_num` makes it).
pub fn places_ordered(value: f64, places: u32) -> i64 {
    let limit = LARGEST_PLACES_INTEGER as f64;
    let scaled = rint(value * TEN[places.min(22) as usize]);
    if scaled.is_nan() {
        return 0;
    }
    scaled.clamp(-limit, limit) as i64
}

/// k / 10**places: one correctly rounded binary64 division.
pub fn places_value(ordered: i64, places: u32) -> f64 {
    ordered as f64 / TEN[places.min(22) as usize]
}

/// The constants of the decimals of `digits` significant digits (§6.9).
#[derive(Debug, Clone)]
pub struct Digits {
    digits: u32,
    /// B = 9 * 10**(p-1), the integers of a decade.
    per_decade: i64,
    /// 10**(p-1), the lowest significand.
    low: i64,
    /// The binary64 nearest 10**E for E = E_min .. E_min + 44, E_min = p - 23.
    powers: [f64; 45],
}

impl Digits {
    /// The constants for `digits` in 1..=15 (clamped there: the caller checks the range).
    pub fn new(digits: u32) -> Digits {
        let digits = digits.clamp(1, 15);
        let low = 10i64.pow(digits - 1);
        let lowest_exponent = digits as i64 - 23;
        let mut powers = [0.0; 45];
        for (offset, power) in powers.iter_mut().enumerate() {
            // the text's correctly rounded value, as Python's float("1eE") reads it
            let text = format!("1e{}", lowest_exponent + offset as i64);
            *power = text.parse().unwrap_or(f64::NAN);
        }
        Digits {
            digits,
            per_decade: 9 * low,
            low,
            powers,
        }
    }

    /// L, the largest ordered decimal integer (its negative is -1 - L).
    pub fn largest(&self) -> i64 {
        45 * self.per_decade
    }

    /// The ordered decimal integer of a finite value rounded to p significant digits: +0 is
    /// 0, -0 is -1, a positive value 1 + decade * B + (m - 10**(p-1)), a negative one -1
    /// minus that of its magnitude (the reference's `digits_ordered`, value by value).
    pub fn ordered(&self, value: f64) -> i64 {
        self.ordered_in_decade(value).0
    }

    /// [`Digits::ordered`], and the decade of the value's magnitude (0 for a zero).
    fn ordered_in_decade(&self, value: f64) -> (i64, i64) {
        let magnitude = value.abs();
        let mut ordered = 0;
        let mut decade = 0;
        if magnitude != 0.0 {
            // searchsorted(powers, magnitude, side="right") - 1, clipped to 0..=44 (numpy
            // sorts a NaN after every number)
            decade = if magnitude.is_nan() {
                44
            } else {
                self.decade(magnitude)
            };
            let shift = 22 - decade as i64; // -22 ..= 22
            let scaled = if shift >= 0 {
                magnitude * TEN[shift as usize]
            } else {
                magnitude / TEN[(-shift) as usize]
            };
            let significand = rint(scaled).clamp(self.low as f64, (10 * self.low - 1) as f64);
            // a NaN's significand casts to i64::MIN, as numpy's cast does on x86-64, and the
            // sums wrap, as numpy's do
            let integer = if significand.is_nan() {
                i64::MIN
            } else {
                significand as i64
            };
            ordered = (decade as i64 * self.per_decade)
                .wrapping_add(integer)
                .wrapping_add(1 - self.low);
        }
        // -1 - ordered for a negative value, without a branch: !x is -1 - x
        let sign = (value.to_bits() as i64) >> 63;
        (ordered ^ sign, decade as i64)
    }

    /// The decade of a magnitude (not NaN): `searchsorted(powers, magnitude, side="right") - 1`
    /// clipped to 0..=44, found from an estimate of log10 by the binary exponent, then a step
    /// or two along the table (a binary search per value cost more than the rest together).
    fn decade(&self, magnitude: f64) -> usize {
        let binary_exponent = ((magnitude.to_bits() >> 52) & 0x7ff) as i64 - 1023;
        // floor(binary_exponent * log10(2)) within one, in integers (78913 / 2**18)
        let estimate = ((binary_exponent * 78913) >> 18) - (self.digits as i64 - 23);
        let mut decade = estimate.clamp(0, 44) as usize;
        // the estimate is the decade or one below, but for the table's rounding: two steps
        // without branches (the signs and decades of positions are not predictable), then
        // the rare rest
        for _ in 0..2 {
            let next = (decade + 1).min(44);
            decade += usize::from((decade < 44) & (self.powers[next] <= magnitude));
        }
        while decade < 44 && self.powers[decade + 1] <= magnitude {
            decade += 1;
        }
        while decade > 0 && self.powers[decade] > magnitude {
            decade -= 1;
        }
        decade
    }

    /// The decade of an ordered integer's magnitude m >= 1, `(m - 1) / B`.
    fn decade_of(&self, magnitude: i64) -> i64 {
        (magnitude - 1).div_euclid(self.per_decade)
    }

    /// The binary64 value of an ordered decimal integer within -1 - L ..= L: m / 10**s or
    /// m * 10**-s, one correctly rounded operation.
    pub fn value(&self, ordered: i64) -> f64 {
        self.value_near(ordered, None)
    }

    /// [`Digits::value`], told the decade the integer's magnitude is likely in (that of the
    /// value it corrects): the division by B is skipped when it is.
    fn value_near(&self, ordered: i64, likely_decade: Option<i64>) -> f64 {
        let sign = ordered >> 63; // 0, or -1 for a negative integer
        let magnitude = ordered ^ sign; // -1 - ordered for a negative one
        let sign_bit = (sign as u64) & (1 << 63);
        if magnitude == 0 {
            return f64::from_bits(sign_bit);
        }
        let index = magnitude - 1;
        let decade = match likely_decade {
            Some(d) if index >= d * self.per_decade && index < (d + 1) * self.per_decade => d,
            _ => self.decade_of(magnitude),
        };
        let significand = (index - decade * self.per_decade + self.low) as f64;
        let shift = 22 - decade;
        let value = if shift > 0 {
            significand / TEN[shift.min(22) as usize]
        } else {
            significand * TEN[(-shift).clamp(0, 22) as usize]
        };
        f64::from_bits(value.to_bits() | sign_bit)
    }

    /// p, the significant digits.
    pub fn digits(&self) -> u32 {
        self.digits
    }
}

// -- correcting (§6.9 "Correcting") ------------------------------------------------------------

/// Whether a correction check failed, the first kind (on the integers) before the second (on
/// the corrected values), as the reference checks the whole array for one, then the other.
#[derive(Default)]
struct Failures {
    integer: bool,
    corrected: bool,
}

impl Failures {
    fn result(
        &self,
        integer: impl FnOnce() -> String,
        corrected: impl FnOnce() -> String,
    ) -> Result<(), Broken> {
        if self.integer {
            Err(value_error(integer()))
        } else if self.corrected {
            Err(value_error(corrected()))
        } else {
            Ok(())
        }
    }
}

/// The decoded positions of §6.9: `exact` (P of §8.1, any number of values) corrected by
/// `residual` (e, the same number) in `domain`, written to `out`. The checks of R41 are the
/// reference's, in its order: a correction out of the domain's range anywhere comes first,
/// then a corrected value that is not one of the domain's. A P that is not finite stays so in
/// the domains other than `float32` (NaN in `float64` and the decimals, as the reference
/// writes it), for the caller's R36 check.
///
/// Refuses (R41) slices of different lengths, which the reference's arrays never are.
pub fn correct(
    exact: &[f64],
    residual: &[i64],
    domain: Domain,
    out: &mut [f64],
) -> Result<(), Broken> {
    if exact.len() != residual.len() || exact.len() != out.len() {
        return Err(value_error(format!(
            "{} positions, {} corrections and {} outputs differ",
            exact.len(),
            residual.len(),
            out.len()
        )));
    }
    match domain {
        Domain::Grid { step } => correct_grid(exact, residual, step, out),
        Domain::Float32 => correct_float32(exact, residual, out),
        Domain::Float64 => correct_float64(exact, residual, out),
        Domain::Places { places } => correct_places(exact, residual, places, out),
        Domain::Digits { digits } => {
            correct_digits(exact, residual, &Digits::new(digits), false, out)
        }
        Domain::Digits32 { digits } => {
            correct_digits(exact, residual, &Digits::new(digits), true, out)
        }
    }
}

fn beyond(value: i64, limit: i64) -> bool {
    value < -limit || value > limit
}

fn correct_grid(exact: &[f64], residual: &[i64], step: f64, out: &mut [f64]) -> Result<(), Broken> {
    let mut failed = Failures::default();
    for ((p, e), o) in exact.iter().zip(residual).zip(out.iter_mut()) {
        failed.integer |= beyond(*e, GRID_LARGEST);
        // one product and one sum, each rounded (Rust never fuses them)
        *o = p + step * (*e as f64);
        failed.corrected |= p.is_finite() && !o.is_finite();
    }
    failed.result(
        || "a correction is beyond +-2**53 in domain grid".into(),
        || "a corrected position is not finite".into(),
    )
}

fn correct_float32(exact: &[f64], residual: &[i64], out: &mut [f64]) -> Result<(), Broken> {
    let mut failed = Failures::default();
    for ((p, e), o) in exact.iter().zip(residual).zip(out.iter_mut()) {
        failed.integer |= beyond(*e, FLOAT32_LARGEST);
        // rounded to binary32 (beyond its range: +-infinity, which e may bring back)
        let ordered = ordered32(*p as f32).wrapping_add(*e);
        failed.corrected |= ordered < FINITE32.0 || ordered > FINITE32.1;
        *o = f64::from(from_ordered32(ordered));
    }
    failed.result(
        || "a correction is beyond +-2**32 in domain float32".into(),
        || "a corrected value is not a finite binary32".into(),
    )
}

fn correct_float64(exact: &[f64], residual: &[i64], out: &mut [f64]) -> Result<(), Broken> {
    let mut failed = Failures::default();
    for ((p, e), o) in exact.iter().zip(residual).zip(out.iter_mut()) {
        if !p.is_finite() {
            *o = f64::NAN;
            continue;
        }
        let ordered = ordered64(*p).wrapping_add(*e); // wraps, as §6.9 says
        failed.corrected |= ordered < FINITE64.0 || ordered > FINITE64.1;
        *o = from_ordered64(ordered);
    }
    failed.result(String::new, || {
        "a corrected value is not a finite binary64".into()
    })
}

fn correct_places(
    exact: &[f64],
    residual: &[i64],
    places: u32,
    out: &mut [f64],
) -> Result<(), Broken> {
    let limit = LARGEST_PLACES_INTEGER;
    let mut failed = Failures::default();
    for ((p, e), o) in exact.iter().zip(residual).zip(out.iter_mut()) {
        failed.integer |= beyond(*e, 2 * limit);
        if !p.is_finite() {
            *o = f64::NAN; // R36, whatever e says
            continue;
        }
        let ordered = places_ordered(*p, places).wrapping_add(*e);
        failed.corrected |= beyond(ordered, limit);
        *o = places_value(ordered, places);
    }
    failed.result(
        || "a correction is beyond +-2**54 in domain decimal-places".into(),
        || "a corrected integer is beyond +-2**53 in domain decimal-places".into(),
    )
}

fn correct_digits(
    exact: &[f64],
    residual: &[i64],
    decimals: &Digits,
    binary32: bool,
    out: &mut [f64],
) -> Result<(), Broken> {
    let limit = decimals.largest();
    let mut failed = Failures::default();
    for ((p, e), o) in exact.iter().zip(residual).zip(out.iter_mut()) {
        failed.integer |= beyond(*e, 2 * limit + 1);
        if !p.is_finite() {
            *o = f64::NAN; // R36, whatever e says
            continue;
        }
        let (before, decade) = decimals.ordered_in_decade(*p);
        let ordered = before.wrapping_add(*e);
        if ordered < -1 - limit || ordered > limit {
            failed.corrected = true;
            continue; // no value: the call fails
        }
        // a small correction stays in P's decade
        let value = decimals.value_near(ordered, Some(decade));
        *o = if binary32 {
            f64::from(value as f32)
        } else {
            value
        };
    }
    let digits = decimals.digits();
    failed.result(
        || format!("a correction is beyond the decimals of {digits} digits"),
        || format!("a corrected integer is not a decimal of {digits} digits"),
    )
}

/// The ordered integers of `values` in a lossless domain (the reference's `ordered_in`): what
/// an encoder's corrections are differences of. `grid` has none: its values are the grid
/// step's multiples, which [`grid_residuals`] computes.
pub fn ordered_in(values: &[f64], domain: Domain, out: &mut [i64]) {
    match domain {
        Domain::Float32 => fill(values, out, |v| ordered32(v as f32)),
        Domain::Places { places } => fill(values, out, |v| places_ordered(v, places)),
        Domain::Digits { digits } | Domain::Digits32 { digits } => {
            let decimals = Digits::new(digits);
            fill(values, out, |v| decimals.ordered(v))
        }
        Domain::Float64 | Domain::Grid { .. } => fill(values, out, ordered64),
    }
}

fn fill(values: &[f64], out: &mut [i64], map: impl Fn(f64) -> i64) {
    for (value, o) in values.iter().zip(out.iter_mut()) {
        *o = map(*value);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zigzag_round_trips_the_extremes() {
        for value in [0, -1, 1, i64::MIN, i64::MAX, 12345, -98765] {
            assert_eq!(unzigzag(zigzag(value)), value);
        }
        assert_eq!(zigzag(-1), 1);
        assert_eq!(zigzag(1), 2);
    }

    #[test]
    fn restore_reads_planes_and_sums_frames_wrapping() {
        // two frames of one integer, 8 planes: u = 1 (e = -1) and u = 2 (s = 1)
        let mut raw = vec![0u8; 16];
        raw[0] = 1;
        raw[1] = 2;
        assert_eq!(restore_chunk(&raw, 2, 8, false, 1).unwrap(), vec![-1, 1]);
        assert_eq!(restore_chunk(&raw, 2, 8, true, 1).unwrap(), vec![-1, 0]);
        // i64::MAX + 1 wraps to i64::MIN
        let big = zigzag(i64::MAX).to_le_bytes();
        let one = zigzag(1).to_le_bytes();
        let mut raw = vec![0u8; 16];
        for plane in 0..8 {
            raw[2 * plane] = big[plane];
            raw[2 * plane + 1] = one[plane];
        }
        assert_eq!(
            restore_chunk(&raw, 2, 8, true, 1).unwrap(),
            vec![i64::MAX, i64::MIN]
        );
    }

    #[test]
    fn restore_refuses_shapes_it_cannot_hold() {
        assert_eq!(
            restore_chunk(&[0; 3], 2, 1, false, 1).unwrap_err().rule,
            CHUNK_RULE
        );
        assert!(restore_chunk(&[0; 9], 1, 9, false, 1).is_err());
        assert!(restore_chunk(&[0; 0], 0, 0, false, 1).is_err());
        assert!(restore_chunk(&[0; 3], 3, 1, false, 2).is_err());
        assert!(restore_chunk(&[0; 3], 3, 1, true, 0).is_err());
        assert!(restore_chunk(&[], usize::MAX, 8, false, 1).is_err());
        assert_eq!(
            restore_chunk(&[], 0, 3, true, 0).unwrap(),
            Vec::<i64>::new()
        );
    }

    #[test]
    fn pack_is_what_restore_reads() {
        let values = [0, -1, 5, i64::MIN, i64::MAX, 300, 7, -8, 9];
        for predict in [false, true] {
            let (planes, raw) = pack_chunk(&values, predict, 3).unwrap();
            assert_eq!(restore_chunk(&raw, 9, planes, predict, 3).unwrap(), values);
        }
        assert_eq!(
            pack_chunk(&[0, 1, -1], false, 3).unwrap(),
            (1, vec![0, 2, 1])
        );
        assert_eq!(pack_chunk(&[], true, 0).unwrap(), (1, vec![]));
        assert!(pack_chunk(&[1, 2], false, 3).is_err());
    }

    #[test]
    fn ordered_maps_are_their_own_inverse() {
        for value in [
            0.0f64,
            -0.0,
            1.5,
            -1.5,
            f64::MAX,
            -f64::MAX,
            f64::MIN_POSITIVE,
            5e-324,
        ] {
            assert_eq!(from_ordered64(ordered64(value)).to_bits(), value.to_bits());
            let single = value as f32;
            assert_eq!(
                from_ordered32(ordered32(single)).to_bits(),
                single.to_bits()
            );
        }
        assert_eq!(ordered64(-0.0), -1);
        assert_eq!(ordered32(-0.0), -1);
        assert_eq!(ordered32(f32::MAX), FINITE32.1);
        assert_eq!(ordered64(-f64::MAX), FINITE64.0);
    }

    #[test]
    fn digits_round_trip_decimals() {
        let decimals = Digits::new(6);
        for value in [0.123456, -7.5, 1e-30, 123456.0, 1e20, -0.0, 0.0] {
            let ordered = decimals.ordered(value);
            let back = decimals.value(ordered);
            assert_eq!(decimals.ordered(back), ordered, "{value}");
        }
        assert_eq!(decimals.ordered(-0.0), -1);
        assert_eq!(decimals.value(-1).to_bits(), (-0.0f64).to_bits());
        assert_eq!(decimals.value(decimals.largest()), 9.99999e27);
    }

    #[test]
    fn rint_is_round_ties_even() {
        let mut value: f64 = 1e-3;
        while value < 1e20 {
            for probe in [
                value,
                value + 0.5,
                -value,
                -value - 0.5,
                value.floor() + 0.5,
            ] {
                assert_eq!(
                    rint(probe).to_bits(),
                    probe.round_ties_even().to_bits(),
                    "{probe}"
                );
            }
            value *= 1.37;
        }
        for probe in [
            0.5,
            1.5,
            2.5,
            -0.5,
            -2.5,
            -0.0,
            0.0,
            4503599627370495.5,
            f64::INFINITY,
        ] {
            assert_eq!(
                rint(probe).to_bits(),
                probe.round_ties_even().to_bits(),
                "{probe}"
            );
        }
        assert!(rint(f64::NAN).is_nan());
    }

    #[test]
    fn decade_is_the_tables_search() {
        for digits in [1, 6, 15] {
            let decimals = Digits::new(digits);
            let mut value = 1e-320;
            while value < 1e300 {
                for probe in [value, value * 0.999_999_999, value * 1.000_000_001] {
                    let above = decimals.powers.partition_point(|power| *power <= probe);
                    assert_eq!(
                        decimals.decade(probe),
                        above.saturating_sub(1).min(44),
                        "{probe}"
                    );
                }
                value *= 1.7;
            }
            for power in decimals.powers {
                let above = decimals.powers.partition_point(|p| *p <= power);
                assert_eq!(decimals.decade(power), above - 1);
            }
            assert_eq!(decimals.decade(f64::INFINITY), 44);
        }
    }

    #[test]
    fn correct_reports_the_integer_check_before_the_value_check() {
        let mut out = [0.0; 2];
        // the second value's correction is out of range, the first's corrected value too
        let error = correct(
            &[f64::MAX, 0.0],
            &[i64::MAX, i64::MIN],
            Domain::Grid { step: 1.0 },
            &mut out,
        )
        .unwrap_err();
        assert_eq!(
            error.detail,
            "a correction is beyond +-2**53 in domain grid"
        );
        let error = correct(
            &[f64::MAX, 0.0],
            &[1 << 52, 0],
            Domain::Grid { step: 1e300 },
            &mut out,
        )
        .unwrap_err();
        assert_eq!(error.detail, "a corrected position is not finite");
        let error =
            correct(&[0.0, 0.0], &[FINITE32.1 + 1, 0], Domain::Float32, &mut out).unwrap_err();
        assert_eq!(error.detail, "a corrected value is not a finite binary32");
        let error = correct(&[0.0], &[FINITE64.1 + 1], Domain::Float64, &mut out[..1]).unwrap_err();
        assert_eq!(error.detail, "a corrected value is not a finite binary64");
        let error = correct(
            &[1.0],
            &[i64::MIN],
            Domain::Digits { digits: 3 },
            &mut out[..1],
        )
        .unwrap_err();
        assert_eq!(
            error.detail,
            "a correction is beyond the decimals of 3 digits"
        );
        let error = correct(&[1.0], &[0], Domain::Grid { step: 1.0 }, &mut out).unwrap_err();
        assert_eq!(error.rule, VALUE_RULE);
    }

    #[test]
    fn float32_brings_an_overflow_back() {
        let mut out = [0.0];
        correct(&[1e300], &[-1], Domain::Float32, &mut out).unwrap();
        assert_eq!(out[0], f64::from(f32::MAX));
    }

    #[test]
    fn non_finite_positions_stay_not_finite() {
        let mut out = [0.0; 2];
        for domain in [
            Domain::Float64,
            Domain::Places { places: 2 },
            Domain::Digits32 { digits: 4 },
        ] {
            correct(&[f64::INFINITY, 1.0], &[5, 0], domain, &mut out).unwrap();
            assert!(out[0].is_nan());
            assert_eq!(out[1], 1.0);
        }
    }

    /// A cheap stand-in for the fuzzer: random bytes, sizes, values and domains never panic.
    #[test]
    fn random_inputs_never_panic() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..3000 {
            let length = (next() % 64) as usize;
            let raw: Vec<u8> = (0..length).map(|_| next() as u8).collect();
            let planes = (next() % 10) as usize;
            let count = (next() % 40) as usize;
            let _ = restore_chunk(&raw, count, planes, next() % 2 == 0, (next() % 7) as usize);
            let exact: Vec<f64> = (0..count).map(|_| f64::from_bits(next())).collect();
            let residual: Vec<i64> = (0..count).map(|_| next() as i64 >> (next() % 64)).collect();
            let domain = match next() % 6 {
                0 => Domain::Grid {
                    step: f64::from_bits(next()),
                },
                1 => Domain::Float32,
                2 => Domain::Float64,
                3 => Domain::Places {
                    places: (next() % 40) as u32,
                },
                4 => Domain::Digits {
                    digits: (next() % 40) as u32,
                },
                _ => Domain::Digits32 {
                    digits: (next() % 40) as u32,
                },
            };
            let mut out = vec![0.0; count];
            let _ = correct(&exact, &residual, domain, &mut out);
            let mut ordered = vec![0; count];
            ordered_in(&exact, domain, &mut ordered);
            let frame_values = (next() % 4) as usize;
            if let Ok((planes, bytes)) = pack_chunk(&residual, true, frame_values) {
                let back = restore_chunk(&bytes, count, planes, true, frame_values).unwrap();
                assert_eq!(back, residual);
            }
        }
    }

    #[test]
    fn named_checks_the_scale() {
        assert_eq!(Domain::named("decimal-places", 0.0, 23), None);
        assert_eq!(Domain::named("decimal-digits", 0.0, 0), None);
        assert_eq!(Domain::named("grid", -1.0, 0), None);
        assert_eq!(Domain::named("float32", 0.0, 0), Some(Domain::Float32));
        assert_eq!(Domain::named("other", 0.0, 0), None);
    }
}
