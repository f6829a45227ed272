//! The binary range coder of §6.14 (LZMA's), its adaptive models, and the binarization of one
//! integer: `RangeEncoder`, `RangeDecoder`, `encode_integer` and `decode_integer` of
//! `tuckercodec/format/adaptive.py`, decision for decision.

use crate::error::Broken;

use super::RULE;

/// Probabilities are 15-bit: the chance that a decision is 0, times 2**15.
const PROB_BITS: u32 = 15;
const PROB_ONE: u32 = 1 << PROB_BITS;
const PROB_INIT: u16 = 1 << (PROB_BITS - 1);
/// A model's n-th update shifts by min(n + FIRST_SHIFT, LAST_SHIFT) (n from 0).
const FIRST_SHIFT: u16 = 2;
const LAST_SHIFT: u16 = 6;
/// The range is renormalized (a byte shifted in or out) whenever it falls below this.
const TOP: u32 = 1 << 24;

/// Models of a context for the exponent steps, and for each of the two bits under the leading
/// one by exponent (§6.14's offsets 2, 34 and 66).
pub const EXPONENT_MODELS: usize = 32;
/// The models of one context (§6.14's 130).
pub const MODELS_PER_CONTEXT: usize = 2 + 4 * EXPONENT_MODELS;
/// The largest exponent (bit length less one) a decoded magnitude may have.
pub const MAX_EXPONENT: u32 = 62;

/// One adaptive model: its probability of a 0 and the shift of its next update.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Model {
    prob: u16,
    shift: u16,
}

impl Model {
    /// Even odds, before its first update.
    pub const FRESH: Model = Model {
        prob: PROB_INIT,
        shift: FIRST_SHIFT,
    };

    /// The model after coding `bit` with it.
    #[inline(always)]
    fn update(&mut self, bit: bool) {
        let p = u32::from(self.prob);
        let s = self.shift;
        // p stays in 1..32767: p + ((32768 - p) >> s) < 32768 and p - (p >> s) >= 1 for s >= 2
        self.prob = if bit {
            (p - (p >> s)) as u16
        } else {
            (p + ((PROB_ONE - p) >> s)) as u16
        };
        self.shift = if s < LAST_SHIFT { s + 1 } else { s };
    }
}

/// The models of one context, in the order of §6.14's table of offsets: zero (0), sign (1), the
/// unary exponent steps (2..34), the first bit under the leading one by exponent (34..66), the
/// second by exponent and first bit (66..130). Named arrays rather than one of 130 models, so
/// that an index below 32 needs no bounds check in the decoder's loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Context {
    zero: Model,
    sign: Model,
    exponent: [Model; EXPONENT_MODELS],
    first: [Model; EXPONENT_MODELS],
    second: [[Model; 2]; EXPONENT_MODELS],
}

/// A fresh context.
pub const FRESH_CONTEXT: Context = Context {
    zero: Model::FRESH,
    sign: Model::FRESH,
    exponent: [Model::FRESH; EXPONENT_MODELS],
    first: [Model::FRESH; EXPONENT_MODELS],
    second: [[Model::FRESH; 2]; EXPONENT_MODELS],
};

/// The model slot of exponent step or bit length index `i` (steps past 31 share the last).
#[inline(always)]
fn slot(i: u32) -> usize {
    (i as usize).min(EXPONENT_MODELS - 1)
}

/// LZMA's range encoder: decisions in, bytes out.
pub struct RangeEncoder {
    /// 33 bits: the low end of the interval and a carry into the bytes not written yet.
    low: u64,
    range: u32,
    /// The last byte out that a carry may still change, and how many bytes it stands for (it
    /// and the 0xFF bytes after it).
    cache: u8,
    cache_size: u64,
    out: Vec<u8>,
}

impl Default for RangeEncoder {
    fn default() -> Self {
        Self::new()
    }
}

impl RangeEncoder {
    /// An empty stream.
    pub fn new() -> Self {
        RangeEncoder {
            low: 0,
            range: u32::MAX,
            cache: 0,
            cache_size: 1,
            out: Vec::new(),
        }
    }

    fn shift_low(&mut self) {
        if self.low < 0xFF00_0000 || self.low > 0xFFFF_FFFF {
            let carry = (self.low >> 32) as u8;
            let mut byte = self.cache;
            loop {
                self.out.push(byte.wrapping_add(carry));
                byte = 0xFF;
                self.cache_size -= 1;
                if self.cache_size == 0 {
                    break;
                }
            }
            self.cache = (self.low >> 24) as u8;
        }
        self.cache_size += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    #[inline(always)]
    fn normalize(&mut self) {
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    /// Codes `bit` with `model`, then updates it.
    #[inline(always)]
    pub fn bit(&mut self, model: &mut Model, bit: bool) {
        let bound = (self.range >> PROB_BITS) * u32::from(model.prob);
        if bit {
            self.low += u64::from(bound);
            self.range -= bound;
        } else {
            self.range = bound;
        }
        model.update(bit);
        self.normalize();
    }

    /// Codes `bit` at even odds, with no model.
    #[inline(always)]
    pub fn direct(&mut self, bit: bool) {
        self.range >>= 1;
        if bit {
            self.low += u64::from(self.range);
        }
        self.normalize();
    }

    /// The stream's bytes: `low` shifted out five times.
    pub fn finish(mut self) -> Vec<u8> {
        for _ in 0..5 {
            self.shift_low();
        }
        self.out
    }
}

/// LZMA's range decoder over a whole payload, which must be used up exactly.
///
/// `Copy`, so that a loop can decode with a copy of its own, which the compiler keeps in
/// registers (a decoder whose address is passed to a call stays in memory).
///
/// A read past the end gives 0 and is remembered ([`RangeDecoder::overrun`]): the reference
/// stops there, so every error the decoder reports afterwards is checked against it first,
/// and the first error reported is the reference's.
#[derive(Clone, Copy)]
pub struct RangeDecoder<'a> {
    data: &'a [u8],
    next: usize,
    range: u32,
    code: u32,
}

impl<'a> RangeDecoder<'a> {
    /// The decoder at the start of `payload`: R46 unless it holds at least 5 bytes and starts
    /// with 0.
    pub fn new(payload: &'a [u8]) -> Result<Self, Broken> {
        match payload {
            [0, a, b, c, d, ..] => Ok(RangeDecoder {
                data: payload,
                next: 5,
                range: u32::MAX,
                code: u32::from_be_bytes([*a, *b, *c, *d]),
            }),
            _ => Err(Broken::new(
                RULE,
                "an adaptive stream starts with a zero byte and holds at least 5 bytes",
            )),
        }
    }

    /// A byte was read past the end of the payload.
    #[inline(always)]
    pub fn overrun(&self) -> bool {
        self.next > self.data.len()
    }

    /// R46 for reading past the end, if it happened.
    #[inline(always)]
    pub fn check_overrun(&self) -> Result<(), Broken> {
        if self.overrun() {
            Err(ends_early())
        } else {
            Ok(())
        }
    }

    #[inline(always)]
    fn normalize(&mut self) {
        while self.range < TOP {
            let byte = self.data.get(self.next).copied().unwrap_or(0);
            // at most one past the end counts: the count cannot overflow
            self.next = self.next.min(self.data.len()) + 1;
            self.range <<= 8;
            self.code = (self.code << 8) | u32::from(byte);
        }
    }

    /// The next decision, with `model`, which is then updated.
    #[inline(always)]
    pub fn bit(&mut self, model: &mut Model) -> bool {
        let bound = (self.range >> PROB_BITS) * u32::from(model.prob);
        let bit = self.code >= bound;
        if bit {
            self.code -= bound;
            self.range -= bound;
        } else {
            self.range = bound;
        }
        model.update(bit);
        self.normalize();
        bit
    }

    /// [`RangeDecoder::bit`] computed with masks instead of branches, for a decision close to
    /// a coin flip whose value nothing branches on (a sign, a bit under the leading one): a
    /// branch on it would be mispredicted about every other time.
    #[inline(always)]
    pub fn data_bit(&mut self, model: &mut Model) -> bool {
        let p = u32::from(model.prob);
        let bound = (self.range >> PROB_BITS) * p;
        let bit = self.code >= bound;
        let one = u32::from(bit).wrapping_neg();
        self.code -= bound & one;
        self.range = (bound & !one) | (self.range.wrapping_sub(bound) & one);
        // Model::update without its branch: a 1 takes p >> s off, a 0 adds (32768 - p) >> s
        let s = model.shift;
        let up = ((PROB_ONE - p) >> s) & !one;
        let down = (p >> s) & one;
        model.prob = (p + up - down) as u16;
        model.shift = if s < LAST_SHIFT { s + 1 } else { s };
        self.normalize();
        bit
    }

    /// The next bit at even odds.
    #[inline(always)]
    pub fn direct(&mut self) -> bool {
        self.range >>= 1;
        let bit = self.code >= self.range;
        if bit {
            self.code -= self.range;
        }
        self.normalize();
        bit
    }

    /// R46 unless the whole payload was read, no more, and `code < range`.
    #[inline]
    pub fn finish(&self) -> Result<(), Broken> {
        self.check_overrun()?;
        if self.next != self.data.len() {
            return Err(Broken::new(
                RULE,
                format!(
                    "the adaptive stream holds {} bytes after its last integer",
                    self.data.len() - self.next
                ),
            ));
        }
        if self.code >= self.range {
            return Err(Broken::new(
                RULE,
                "the adaptive stream's last bytes are not a range coder's ending",
            ));
        }
        Ok(())
    }
}

/// Binarizes `value` (§6.14) and codes its decisions with the models of `context`.
#[inline]
pub fn encode_integer(coder: &mut RangeEncoder, context: &mut Context, value: i64) {
    if value == 0 {
        coder.bit(&mut context.zero, false);
        return;
    }
    coder.bit(&mut context.zero, true);
    coder.bit(&mut context.sign, value < 0);
    let magnitude = value.unsigned_abs();
    let exponent = 63 - magnitude.leading_zeros();
    for i in 0..exponent {
        coder.bit(&mut context.exponent[slot(i)], true);
    }
    coder.bit(&mut context.exponent[slot(exponent)], false);
    if exponent >= 1 {
        let first = (magnitude >> (exponent - 1)) & 1 == 1;
        coder.bit(&mut context.first[slot(exponent)], first);
        if exponent >= 2 {
            let second = (magnitude >> (exponent - 2)) & 1 == 1;
            coder.bit(
                &mut context.second[slot(exponent)][usize::from(first)],
                second,
            );
            for shift in (0..exponent - 2).rev() {
                coder.direct((magnitude >> shift) & 1 == 1);
            }
        }
    }
}

/// The inverse of [`encode_integer`]: R46 for a magnitude of more than 63 bits, or (first) for
/// a read past the end of the payload.
#[inline(always)]
pub fn decode_integer(coder: &mut RangeDecoder<'_>, context: &mut Context) -> Result<i64, Broken> {
    if !coder.bit(&mut context.zero) {
        return Ok(0);
    }
    let negative = coder.data_bit(&mut context.sign);
    // the exponent in unary: the loop's bound keeps the index in the array, unchecked
    let mut exponent = 0;
    while exponent < EXPONENT_MODELS - 1 && coder.bit(&mut context.exponent[exponent]) {
        exponent += 1;
    }
    if exponent == EXPONENT_MODELS - 1 {
        // a magnitude of 2**31 or more: the steps from the 32nd on share the last model
        let model = &mut context.exponent[EXPONENT_MODELS - 1];
        while coder.bit(model) {
            exponent += 1;
            if exponent > MAX_EXPONENT as usize {
                coder.check_overrun()?;
                return Err(too_long());
            }
        }
    }
    let mut magnitude = 1u64;
    if exponent >= 1 {
        let e = exponent.min(EXPONENT_MODELS - 1);
        let first = coder.data_bit(&mut context.first[e]);
        magnitude = 2 | u64::from(first);
        if exponent >= 2 {
            let second = coder.data_bit(&mut context.second[e][usize::from(first)]);
            magnitude = (magnitude << 1) | u64::from(second);
            for _ in 2..exponent {
                magnitude = (magnitude << 1) | u64::from(coder.direct());
            }
        }
    }
    // exponent <= 62: the magnitude is below 2**63
    let value = magnitude as i64;
    Ok(if negative { -value } else { value })
}

/// R46 for a read past the end. The errors are made out of line, to keep the loops small.
#[cold]
#[inline(never)]
fn ends_early() -> Broken {
    Broken::new(RULE, "the adaptive stream ends before its last integer")
}

/// R46 for a magnitude of more than 63 bits.
#[cold]
#[inline(never)]
fn too_long() -> Broken {
    Broken::new(
        RULE,
        format!("an integer of the adaptive stream has more than {MAX_EXPONENT} bits"),
    )
}
